//! The bench's tables: the comparison of the bank against the others case by case, the
//! wheel-surfaces it misses, where the table estimator's latency goes, and the CSV fields.

use super::super::table_estimator::Hold;
use super::cases::Case;
use super::metrics::{Common, HoldTally, Metrics, WheelSurface, GROSS, TARGET_LATENCY};
use super::{BANK, METHODS};
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

/// "The bank against the others, case by case": for each case, every measure on which another
/// estimator does better than the bank (index 3 of [`METHODS`]) — more wheel-surfaces within
/// ±0.1 within [`TARGET_LATENCY`], a lower p95 error or a smaller share off by more than
/// [`GROSS`] while identifiable (where it is identifiable at all), a shorter median latency —
/// the p95 error and the count off by more than [`GROSS`] also like for like, on the samples
/// both call identifiable ([`Common`], `commons[m]`), and per other estimator how many cases
/// the bank is level or ahead on each measure.
pub fn against_the_others(per_case: &[(&Case, Vec<Metrics>, Vec<Common>)]) -> String {
    let mut md = format!(
        "\n## The bank against the others, case by case\n\nWhere another estimator does better than the bank on one of the issue's measures: wheel-surfaces within ±0.1 within {TARGET_LATENCY} s of utilisation 0.5 (ws), p95 error while identifiable (p95, with the identifiable samples n; and like for like, on the samples both call identifiable), share of the case's samples identifiable and off by > {GROSS} (gross; like for like: count off by > {GROSS} on the samples both call identifiable), median latency (latency; like for like: over the wheel-surfaces both settle on). Cases not listed: the bank level or ahead on all of them.\n\n| manoeuvre | road | behind on |\n|---|---|---|\n"
    );
    // Per other estimator: [ws, p95, gross, latency, and p95, gross, latency like for like]
    // as (bank level or ahead, comparable).
    let mut tally = [[(0usize, 0usize); 7]; METHODS.len()];
    for (c, ms, commons) in per_case {
        let Some(b) = ms.get(BANK) else { continue };
        let mut behind = Vec::new();
        for (m, o) in ms.iter().enumerate().filter(|&(m, _)| m != BANK) {
            let name = METHODS[m];
            let t = &mut tally[m];
            let cm = commons.get(m).cloned().unwrap_or_default();
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
    for (m, t) in tally.iter().enumerate().filter(|&(m, _)| m != BANK) {
        let name = METHODS[m];
        let _ = writeln!(
            md,
            "bank against {name}: ws level or ahead on {} of {} cases; p95 on {} of {} (both identifiable; like for like on {} of {}); gross on {} of {} ({name} identifiable; like for like on {} of {}); latency on {} of {} ({name} with one; like for like on {} of {}).",
            t[0].0, t[0].1, t[1].0, t[1].1, t[4].0, t[4].1, t[2].0, t[2].1, t[5].0, t[5].1, t[3].0, t[3].1, t[6].0, t[6].1
        );
    }
    md
}

/// The "where the latency goes" table (Markdown, and CSV with one row per case and a total).
pub(super) fn hold_tables(tallies: &[(&Case, HoldTally)]) -> (String, String) {
    let mut md = String::from(
        "\n## Where the Gough estimator's latency goes\n\nPer case, over the wheels' surfaces that reach utilisation 0.5 (\"wheel-surfaces\"): how many settle within ±0.1 of the truth within 150 ms, and what the estimator reported over the samples of that window (from utilisation 0.5 until it settles, at most 150 ms): held, and why (`MuEstimator::last_hold`), or identifiable but not yet for good within ±0.1.\n\n| manoeuvre | road | wheel-surfaces | within 150 ms |",
    );
    let mut csv = String::from("manoeuvre,road,wheel_surfaces,within_150ms");
    for h in Hold::ALL {
        let _ = write!(md, " {} |", h.name());
        let _ = write!(csv, ",{}", h.name());
    }
    md.push_str(" identifiable |\n|---|---|---|---|");
    csv.push_str(",identifiable\n");
    for _ in 0..=Hold::ALL.len() {
        md.push_str("---|");
    }
    md.push('\n');
    let mut total = HoldTally::default();
    let mut row = |man: &str, road: &str, t: &HoldTally| {
        let _ = write!(md, "| {man} | {road} | {} | {} |", t.windows, t.within);
        let _ = write!(
            csv,
            "{},{},{},{}",
            csv_field(man),
            csv_field(road),
            t.windows,
            t.within
        );
        for x in t.shares() {
            if t.total() == 0 {
                md.push_str(" – |");
                csv.push(',');
            } else {
                let _ = write!(md, " {:.0} % |", 100.0 * x);
                let _ = write!(csv, ",{x:.4}");
            }
        }
        md.push('\n');
        csv.push('\n');
    };
    for (c, t) in tallies {
        row(c.manoeuvre, &c.road, t);
        total.add(t);
    }
    row("all", "", &total);
    (md, csv)
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
        let case = Case {
            manoeuvre: "slalom",
            road: "mu=0.1".into(),
        };
        let level = Case {
            manoeuvre: "slalom",
            road: "mu=0.5".into(),
        };
        // Like for like: on the 20 samples both call identifiable, the bank's p95 is lower than
        // the table estimator's, and slip-slope is off by > 0.2 less often.
        let like = vec![
            Common {
                n: 20,
                p95: (Some(0.005), Some(0.01)),
                gross: (0, 0),
                latency: (Some(0.04), Some(0.5), 1),
            },
            Common::default(),
            Common {
                n: 50,
                p95: (Some(0.01), Some(0.05)),
                gross: (3, 1),
                latency: (Some(0.05), Some(0.0), 3),
            },
            Common::default(),
        ];
        let md = against_the_others(&[
            (
                &case,
                vec![better_p95, silent.clone(), more_ws, bank.clone()],
                like,
            ),
            (
                &level,
                vec![silent.clone(), silent, Metrics::default(), bank],
                vec![Common::default(); 4],
            ),
        ]);
        let row = md
            .lines()
            .find(|l| l.starts_with("| slalom | mu=0.1 |"))
            .unwrap();
        assert!(
            row.contains("gough: p95 0.010 < 0.020 (n 20 vs 1000)"),
            "{row}"
        );
        assert!(row.contains("gough: gross 0.00 % < 0.40 %"), "{row}");
        assert!(
            !row.contains("gough: ws") && !row.contains("gough: latency"),
            "{row}"
        );
        assert!(row.contains("slip-slope: ws 4 > 3"), "{row}");
        assert!(row.contains("slip-slope: latency 0.000 < 0.050 s"), "{row}");
        assert!(!row.contains("hsu-gerdes"), "{row}");
        assert!(!row.contains("gough: p95 like for like"), "{row}");
        assert!(
            row.contains("slip-slope: off by > 0.2 like for like 1 < 3 (n 50)"),
            "{row}"
        );
        assert!(!md.contains("| slalom | mu=0.5 |"), "{md}");
        assert!(md.contains("bank against gough: ws level or ahead on 2 of 2 cases; p95 on 0 of 1 (both identifiable; like for like on 1 of 1); gross on 0 of 1 (gough identifiable; like for like on 1 of 1); latency on 1 of 1 (gough with one; like for like on 1 of 1)"), "{md}");
        assert!(
            md.contains(
                "bank against hsu-gerdes: ws level or ahead on 2 of 2 cases; p95 on 0 of 0"
            ),
            "{md}"
        );
        assert!(
            md.contains("bank against slip-slope: ws level or ahead on 1 of 2 cases"),
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
