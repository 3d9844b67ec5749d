//! The bench's tables: a row per case and estimator (`table.md`, `table.csv`), the closing
//! lines per estimator over the suite, the bank against the others case by case, the
//! wheel-surfaces the bank misses; and the CSV fields.

use super::cases::Case;
use super::metrics::{Common, Metrics, Totals, WheelSurface, GROSS, TARGET_LATENCY};
use crate::mu::Method;
use std::fmt::Write as _;

/// A CSV field as RFC 4180 has it: quoted (inner quotes doubled) when it holds a comma, a quote
/// or a line break — a road spec such as `step=1.0@0,0.3@90` does.
pub(crate) fn csv_field(s: &str) -> std::borrow::Cow<'_, str> {
    if s.contains([',', '"', '\n', '\r']) {
        format!("\"{}\"", s.replace('"', "\"\"")).into()
    } else {
        s.into()
    }
}

pub(crate) fn fmt(x: Option<f64>, digits: usize) -> String {
    x.map_or("–".into(), |v| format!("{v:.digits$}"))
}

/// Wheel names in the order of the traces.
pub(crate) const WHEELS: [&str; 4] = ["fl", "fr", "rl", "rr"];

/// "Wheel-surfaces the bank does not read within 150 ms": one row per miss (`wheels.csv` has
/// every wheel-surface).
pub(super) fn misses_table(misses: &[(&Case, WheelSurface)]) -> String {
    let mut md = format!(
        "\n## Wheel-surfaces the bank does not read within {TARGET_LATENCY} s\n\n\
         Each wheel on each stretch of one μ that reaches utilisation 0.5, where the bank's estimate \
         does not stay within ±0.1 from at most {TARGET_LATENCY} s after that (out/mu_bench/wheels.csv \
         lists every wheel-surface):\n\n\
         | manoeuvre | road | wheel | μ | stretch [s] | utilisation 0.5 at [s] | latency [s] |\n\
         |---|---|---|---|---|---|---|\n"
    );
    for (c, x) in misses {
        let _ = writeln!(
            md,
            "| {} | {} | {} | {} | {:.3}–{:.3} | {:.3} | {} |",
            c.manoeuvre,
            c.road,
            WHEELS.get(x.wheel).copied().unwrap_or("?"),
            x.mu,
            x.t_start,
            x.t_end,
            x.t_util05,
            x.latency
                .map_or("never for 50 rows".into(), |l| format!("{l:.3}")),
        );
    }
    md
}

/// One estimator's results on one case.
#[derive(Debug, Clone)]
pub struct MethodResult {
    /// The estimator.
    pub method: Method,
    /// Its metrics over the case's wheels.
    pub metrics: Metrics,
    /// It against the bank on the samples both call identifiable (empty for the bank itself).
    pub common: Common,
}

/// The header of `table.md`.
pub const MD_HEADER: &str = "| manoeuvre | road | estimator | identifiable samples | mean err | p95 err | within 2σ | off by > 0.2 | util when within ±0.1 | latency from util 0.5 [s] | detect change [s] |\n|---|---|---|---|---|---|---|---|---|---|---|\n";

/// The header of `table.csv`.
pub const CSV_HEADER: &str = "manoeuvre,road,estimator,n_identifiable,err_mean,err_p95,within_2sigma,gross,util_within,latency_s,detect_s,false_alarms,ws_within,ws_total\n";

/// The row of `table.md` of estimator `m` on case `c`.
pub fn md_row(c: &Case, m: Method, mt: &Metrics) -> String {
    format!(
        "| {} | {} | {} | {} | {} | {} | {} | {:.2} % | {} | {} | {} |\n",
        c.manoeuvre,
        c.road,
        m.name(),
        mt.n_identifiable,
        fmt(mt.err_mean, 3),
        fmt(mt.err_p95, 3),
        mt.within_2sigma
            .map_or("–".into(), |x| format!("{:.1} %", 100.0 * x)),
        100.0 * mt.gross,
        fmt(mt.util_within, 2),
        fmt(mt.latency, 3),
        fmt(mt.detect, 3),
    )
}

/// The row of `table.csv` of estimator `m` on case `c`.
pub fn csv_row(c: &Case, m: Method, mt: &Metrics) -> String {
    format!(
        "{},{},{},{},{},{},{},{:.5},{},{},{},{},{},{}\n",
        csv_field(c.manoeuvre),
        csv_field(&c.road),
        m.name(),
        mt.n_identifiable,
        fmt(mt.err_mean, 4),
        fmt(mt.err_p95, 4),
        fmt(mt.within_2sigma, 4),
        mt.gross,
        fmt(mt.util_within, 3),
        fmt(mt.latency, 4),
        fmt(mt.detect, 4),
        mt.false_alarms,
        mt.ws_within,
        mt.ws_total
    )
}

/// The row of `wheels.csv` of wheel-surface `x` of case `c`.
pub fn wheel_row(c: &Case, x: &WheelSurface) -> String {
    format!(
        "{},{},{},{},{:.3},{:.3},{:.3},{},{}\n",
        csv_field(c.manoeuvre),
        csv_field(&c.road),
        WHEELS.get(x.wheel).copied().unwrap_or("?"),
        x.mu,
        x.t_start,
        x.t_end,
        x.t_util05,
        fmt(x.latency, 3),
        x.within()
    )
}

/// The closing lines over the suite: per estimator (`totals`, in the bench's order) the cases
/// and wheel-surfaces within ±0.1 within [`TARGET_LATENCY`], the change flags, the worst p95
/// and gross error; the same without the straight ABS stops; and the identifiable shares.
/// `cases`: the suite's cases, `issue_cases`: those of them not straight stops.
pub fn summary(totals: &[(Method, Totals)], cases: usize, issue_cases: usize) -> String {
    let mut s = String::new();
    for (m, t) in totals {
        let _ = writeln!(
            s,
            "{}: within ±0.1 within {TARGET_LATENCY} s of utilisation 0.5 on {} of {cases} cases and {} of {} wheel-surfaces; {} false change alarms of {} change flags; worst p95 error {}; worst share of samples identifiable and off by > {GROSS}: {:.2} %.",
            m.name(),
            t.within,
            t.ws.0,
            t.ws.1,
            t.alarms,
            t.flags,
            fmt(t.worst_p95, 3),
            100.0 * t.worst_gross,
        );
    }
    for (m, t) in totals {
        let _ = writeln!(
            s,
            "{}, without the straight ABS stops: within ±0.1 within {TARGET_LATENCY} s of utilisation 0.5 on {} of {issue_cases} cases and {} of {} wheel-surfaces.",
            m.name(),
            t.within_issue,
            t.ws_issue.0,
            t.ws_issue.1,
        );
    }
    for (m, t) in totals {
        let (i, n, ih, nh) = t.shares;
        let pct = |a: usize, b: usize| 100.0 * a as f64 / b.max(1) as f64;
        let _ = writeln!(
            s,
            "{}: identifiable on {:.1} % of the suite's samples ({i} of {n}), {:.1} % of those at utilisation 0.5 or more ({ih} of {nh}).",
            m.name(),
            pct(i, n),
            pct(ih, nh),
        );
    }
    s
}

/// "The bank against the others, case by case": for each case, every measure on which another
/// estimator does better than the bank — more wheel-surfaces within ±0.1 within
/// [`TARGET_LATENCY`], a lower p95 error or a smaller share off by more than [`GROSS`] while
/// identifiable (where it is identifiable at all), a shorter median latency — the p95 error and
/// the count off by more than [`GROSS`] also like for like, on the samples both call
/// identifiable ([`MethodResult::common`]), and per other estimator how many cases the bank is
/// level or ahead on each measure. A case without the bank's results is left out.
pub fn against_the_others(per_case: &[(&Case, Vec<MethodResult>)]) -> String {
    let mut md = format!(
        "\n## The bank against the others, case by case\n\nWhere another estimator does better than the bank on one of the issue's measures: wheel-surfaces within ±0.1 within {TARGET_LATENCY} s of utilisation 0.5 (ws), p95 error while identifiable (p95, with the identifiable samples n; and like for like, on the samples both call identifiable), share of the case's samples identifiable and off by > {GROSS} (gross; like for like: count off by > {GROSS} on the samples both call identifiable), median latency (latency; like for like: over the wheel-surfaces both settle on). Cases not listed: the bank level or ahead on all of them.\n\n| manoeuvre | road | behind on |\n|---|---|---|\n"
    );
    // Per other estimator (in the bench's order): [ws, p95, gross, latency, and p95, gross,
    // latency like for like] as (bank level or ahead, comparable).
    let mut tally: Vec<(Method, [(usize, usize); 7])> = Method::ALL
        .iter()
        .filter(|&&m| m != Method::Bank)
        .map(|&m| (m, [(0, 0); 7]))
        .collect();
    for (c, results) in per_case {
        let Some(b) = results.iter().find(|r| r.method == Method::Bank) else {
            continue;
        };
        let b = &b.metrics;
        let mut behind = Vec::new();
        for r in results.iter().filter(|r| r.method != Method::Bank) {
            let Some((_, t)) = tally.iter_mut().find(|(m, _)| *m == r.method) else {
                continue;
            };
            let (name, o, cm) = (r.method.name(), &r.metrics, &r.common);
            // One comparable measure: counted, and listed when the bank is behind.
            let mut measure = |i: usize, ok: bool, why: &dyn Fn() -> String| {
                t[i].1 += 1;
                t[i].0 += usize::from(ok);
                if !ok {
                    behind.push(format!("{name}: {}", why()));
                }
            };
            measure(0, o.ws_within <= b.ws_within, &|| {
                format!("ws {} > {}", o.ws_within, b.ws_within)
            });
            if let (Some(x), Some(y)) = (o.err_p95, b.err_p95) {
                measure(1, y <= x, &|| {
                    format!(
                        "p95 {x:.3} < {y:.3} (n {} vs {})",
                        o.n_identifiable, b.n_identifiable
                    )
                });
            }
            if let (Some(y), Some(x)) = cm.p95 {
                measure(4, y <= x, &|| {
                    format!("p95 like for like {x:.3} < {y:.3} (n {})", cm.n)
                });
            }
            if o.n_identifiable > 0 {
                measure(2, b.gross <= o.gross, &|| {
                    format!("gross {:.2} % < {:.2} %", 100.0 * o.gross, 100.0 * b.gross)
                });
            }
            if cm.n > 0 {
                measure(5, cm.gross.0 <= cm.gross.1, &|| {
                    format!(
                        "off by > {GROSS} like for like {} < {} (n {})",
                        cm.gross.1, cm.gross.0, cm.n
                    )
                });
            }
            if let (Some(y), Some(x), n) = cm.latency {
                measure(6, y <= x, &|| {
                    format!("latency like for like {x:.3} < {y:.3} s (over {n} wheel-surfaces)")
                });
            }
            if let Some(x) = o.latency {
                measure(3, b.latency.is_some_and(|y| y <= x), &|| {
                    format!(
                        "latency {x:.3} < {} s (over {} vs {} wheel-surfaces)",
                        fmt(b.latency, 3),
                        o.ws_within,
                        b.ws_within
                    )
                });
            }
        }
        if !behind.is_empty() {
            let _ = writeln!(
                md,
                "| {} | {} | {} |",
                c.manoeuvre,
                c.road,
                behind.join("; ")
            );
        }
    }
    md.push('\n');
    for (m, t) in &tally {
        let name = m.name();
        let _ = writeln!(
            md,
            "bank against {name}: ws level or ahead on {} of {} cases; p95 on {} of {} (both identifiable; like for like on {} of {}); gross on {} of {} ({name} identifiable; like for like on {} of {}); latency on {} of {} ({name} with one; like for like on {} of {}).",
            t[0].0, t[0].1, t[1].0, t[1].1, t[4].0, t[4].1, t[2].0, t[2].1, t[5].0, t[5].1, t[3].0, t[3].1, t[6].0, t[6].1
        );
    }
    md
}

/// "Warm start: the vehicle suite" (`--warm`): the bank on each case cold and warm (its second
/// run in a row on one estimator, the clock continued), each cell "cold / warm", and the
/// closing lines of both.
pub fn warm_vehicle(
    rows: &[(&Case, Metrics, Metrics)],
    totals: &(Totals, Totals),
    cases: usize,
    issue_cases: usize,
) -> String {
    let mut md = String::from(
        "\n## Warm start: the vehicle suite\n\n\
         The bank on every case twice in a row on one estimator (its clock continued): cold is the \
         first run, warm the second, from the state the first left. Each cell: cold / warm.\n\n\
         | manoeuvre | road | wheel-surfaces within 150 ms | p95 err | off by > 0.2 | latency from util 0.5 [s] | detect change [s] | false change flags (of flags) | identifiable samples |\n\
         |---|---|---|---|---|---|---|---|---|\n",
    );
    for (c, a, b) in rows {
        let _ = writeln!(
            md,
            "| {} | {} | {} of {} / {} of {} | {} / {} | {:.2} % / {:.2} % | {} / {} | {} / {} | {} of {} / {} of {} | {} / {} |",
            c.manoeuvre,
            c.road,
            a.ws_within,
            a.ws_total,
            b.ws_within,
            b.ws_total,
            fmt(a.err_p95, 3),
            fmt(b.err_p95, 3),
            100.0 * a.gross,
            100.0 * b.gross,
            fmt(a.latency, 3),
            fmt(b.latency, 3),
            fmt(a.detect, 3),
            fmt(b.detect, 3),
            a.false_alarms,
            a.change_flags,
            b.false_alarms,
            b.change_flags,
            a.n_identifiable,
            b.n_identifiable,
        );
    }
    md.push('\n');
    for (name, t) in [("cold", &totals.0), ("warm", &totals.1)] {
        let s = summary(&[(Method::Bank, t.clone())], cases, issue_cases);
        for line in s.lines() {
            let _ = writeln!(md, "{name}: {line}");
        }
    }
    md
}

/// `seeds.md` of [`super::run_seeds`]: per seed and the worst over them, the bank's closing
/// figures on the vehicle suite, and the wheel cases per level at the standard rate.
pub fn seeds(reports: &[(u64, super::Report)]) -> String {
    let list: Vec<String> = reports.iter().map(|(s, _)| s.to_string()).collect();
    let mut md = format!(
        "# gough mu bench over noise seeds {}

Each seed's tables: seed-N/table.md.
",
        list.join(", ")
    );
    let vehicle: Vec<(u64, &(Totals, usize, usize))> = reports
        .iter()
        .filter_map(|(s, r)| r.vehicle.as_ref().map(|v| (*s, v)))
        .collect();
    if !vehicle.is_empty() {
        md.push_str(
            "\n## The vehicle suite: the bank\n\n\
             | seed | cases within 150 ms (issue's) | wheel-surfaces within 150 ms (issue's) | cases within 150 ms (all) | wheel-surfaces within 150 ms (all) | false change alarms (of flags) | worst p95 | worst off by > 0.2 |\n\
             |---|---|---|---|---|---|---|---|\n",
        );
        let row = |md: &mut String, name: &str, t: &Totals, n: usize, issue: usize| {
            let _ = writeln!(
                md,
                "| {name} | {} of {issue} | {} of {} | {} of {n} | {} of {} | {} of {} | {} | {:.2} % |",
                t.within_issue,
                t.ws_issue.0,
                t.ws_issue.1,
                t.within,
                t.ws.0,
                t.ws.1,
                t.alarms,
                t.flags,
                fmt(t.worst_p95, 3),
                100.0 * t.worst_gross,
            );
        };
        for (seed, (t, n, issue)) in &vehicle {
            row(&mut md, &seed.to_string(), t, *n, *issue);
        }
        // The worst: the fewest within, the most alarms, the largest errors.
        let mut w = vehicle[0].1 .0.clone();
        for (_, (t, ..)) in &vehicle[1..] {
            w.within = w.within.min(t.within);
            w.within_issue = w.within_issue.min(t.within_issue);
            w.ws.0 = w.ws.0.min(t.ws.0);
            w.ws_issue.0 = w.ws_issue.0.min(t.ws_issue.0);
            w.alarms = w.alarms.max(t.alarms);
            w.flags = w.flags.max(t.flags);
            w.worst_p95 = match (w.worst_p95, t.worst_p95) {
                (Some(a), Some(b)) => Some(a.max(b)),
                (a, b) => a.or(b),
            };
            w.worst_gross = w.worst_gross.max(t.worst_gross);
        }
        let (_, (_, n, issue)) = vehicle[0];
        row(&mut md, "worst", &w, *n, *issue);
    }
    let wheel: Vec<(u64, &[(super::wheel::Level, super::wheel::tables::Tally)])> = reports
        .iter()
        .filter(|(_, r)| !r.wheel.is_empty())
        .map(|(s, r)| (*s, r.wheel.as_slice()))
        .collect();
    md.push_str(&super::wheel::tables::seeds(&wheel));
    md
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The comparison lists exactly the measures on which another estimator beats the bank,
    /// and counts the rest level or ahead; an estimator never identifiable is not compared on
    /// p95 or gross.
    #[test]
    fn the_comparison_lists_where_the_bank_is_behind() {
        let bank = Metrics {
            n_identifiable: 1000,
            err_p95: Some(0.02),
            gross: 0.004,
            latency: Some(0.05),
            ws_within: 3,
            ws_total: 4,
            ..Metrics::default()
        };
        let silent = Metrics {
            ws_total: 4,
            ..Metrics::default()
        };
        let better_p95 = Metrics {
            n_identifiable: 20,
            err_p95: Some(0.01),
            gross: 0.0,
            latency: Some(0.5),
            ws_within: 1,
            ws_total: 4,
            ..Metrics::default()
        };
        let more_ws = Metrics {
            n_identifiable: 50,
            err_p95: Some(0.05),
            gross: 0.01,
            latency: Some(0.0),
            ws_within: 4,
            ws_total: 4,
            ..Metrics::default()
        };
        let case = Case::new("slalom", "mu=0.1").unwrap();
        let level = Case::new("slalom", "mu=0.5").unwrap();
        let r = |method, metrics: &Metrics, common| MethodResult {
            method,
            metrics: metrics.clone(),
            common,
        };
        // Like for like: on the 20 samples both call identifiable, the bank's p95 is lower than
        // Hsu–Gerdes', and slip-slope is off by > 0.2 less often.
        let like_hsu = Common {
            n: 20,
            p95: (Some(0.005), Some(0.01)),
            gross: (0, 0),
            latency: (Some(0.04), Some(0.5), 1),
        };
        let like_slip = Common {
            n: 50,
            p95: (Some(0.01), Some(0.05)),
            gross: (3, 1),
            latency: (Some(0.05), Some(0.0), 3),
        };
        let no = Common::default();
        let md = against_the_others(&[
            (
                &case,
                vec![
                    r(Method::HsuGerdes, &better_p95, like_hsu),
                    r(Method::SlipSlope, &more_ws, like_slip.clone()),
                    r(Method::Bank, &bank, no.clone()),
                ],
            ),
            (
                &level,
                vec![
                    r(Method::HsuGerdes, &silent, no.clone()),
                    r(Method::SlipSlope, &Metrics::default(), no.clone()),
                    r(Method::Bank, &bank, no.clone()),
                ],
            ),
        ]);
        let row = md
            .lines()
            .find(|l| l.starts_with("| slalom | mu=0.1 |"))
            .unwrap();
        assert!(
            row.contains("hsu-gerdes: p95 0.010 < 0.020 (n 20 vs 1000)"),
            "{row}"
        );
        assert!(row.contains("hsu-gerdes: gross 0.00 % < 0.40 %"), "{row}");
        assert!(
            !row.contains("hsu-gerdes: ws") && !row.contains("hsu-gerdes: latency"),
            "{row}"
        );
        assert!(row.contains("slip-slope: ws 4 > 3"), "{row}");
        assert!(row.contains("slip-slope: latency 0.000 < 0.050 s"), "{row}");
        assert!(!row.contains("hsu-gerdes: p95 like for like"), "{row}");
        assert!(
            row.contains("slip-slope: off by > 0.2 like for like 1 < 3 (n 50)"),
            "{row}"
        );
        assert!(!md.contains("| slalom | mu=0.5 |"), "{md}");
        assert!(md.contains("bank against hsu-gerdes: ws level or ahead on 2 of 2 cases; p95 on 0 of 1 (both identifiable; like for like on 1 of 1); gross on 0 of 1 (hsu-gerdes identifiable; like for like on 1 of 1); latency on 1 of 1 (hsu-gerdes with one; like for like on 1 of 1)"), "{md}");
        assert!(
            md.contains("bank against slip-slope: ws level or ahead on 1 of 2 cases"),
            "{md}"
        );
        // An estimator never identifiable is listed nowhere and compared on ws alone.
        let md = against_the_others(&[
            (
                &case,
                vec![
                    r(Method::HsuGerdes, &silent, no.clone()),
                    r(Method::SlipSlope, &more_ws, like_slip),
                    r(Method::Bank, &bank, no.clone()),
                ],
            ),
            (
                &level,
                vec![
                    r(Method::HsuGerdes, &silent, no.clone()),
                    r(Method::Bank, &bank, no),
                ],
            ),
        ]);
        let row = md
            .lines()
            .find(|l| l.starts_with("| slalom | mu=0.1 |"))
            .unwrap();
        assert!(!row.contains("hsu-gerdes"), "{row}");
        assert!(
            md.contains(
                "bank against hsu-gerdes: ws level or ahead on 2 of 2 cases; p95 on 0 of 0"
            ),
            "{md}"
        );
    }

    /// A road spec with a comma stays one field of table.csv.
    #[test]
    fn csv_fields_with_commas_are_quoted() {
        assert_eq!(csv_field("mu=0.5"), "mu=0.5");
        assert_eq!(csv_field("step=1.0@0,0.3@90"), "\"step=1.0@0,0.3@90\"");
        assert_eq!(csv_field("a\"b"), "\"a\"\"b\"");
    }
}
