//! The vehicle simulation against facts one can check by hand: steady cornering gives
//! ay = V²/R, a straight coast-down has no side force, the loads sum to the weight, a low-μ road
//! caps ay near μ·g, the ABS keeps slips bounded and stops shorter than locked wheels on μ-split
//! with the yaw moment towards the high-μ side, runs are bit-identical, bad road specs are
//! refused; and the `gough sim` command writes its log and plots or fails in one line.
//!
//! Runs are short (a few simulated seconds each) so the file stays fast in debug builds.
use gough::math::Libm;
use gough::mf::{self, Input, Options, Params};
use gough_host::sim::{
    simulate, Initial, Log, Manoeuvre, Overrides, Road, SimConfig, Vehicle, VehicleParams, G,
};
use std::path::PathBuf;
use std::process::Command;

fn tyre() -> Params<f64> {
    gough::tir::parse(include_str!("../data/tyres/MagicFormula61_Parameters.tir"))
        .unwrap()
        .params
}

fn run(cfg: &SimConfig) -> Log {
    simulate(cfg, &tyre(), false).unwrap()
}

fn named(name: &str) -> SimConfig {
    SimConfig::new(Manoeuvre::by_name(name, &Overrides::default()).unwrap())
}

/// A driver holding a 60 m circle while the speed ramps 12 → 16.8 m/s: once settled, ay = V²/R
/// within 2 % and the CG stays on the circle within 0.1 m.
#[test]
fn constant_radius_gives_v_squared_over_r() {
    let r = 60.0;
    let mut cfg = SimConfig::new(Manoeuvre::ConstantRadius {
        speed: 12.0,
        radius: r,
        accel: 0.4,
    });
    cfg.duration = 12.0;
    let log = run(&cfg);
    let mut checked = 0;
    for rec in log.records.iter().filter(|x| x.t > 4.0) {
        let v = &rec.vehicle;
        let speed = v.vx.hypot(v.vy);
        let want = speed * speed / r;
        assert!(
            (v.ay - want).abs() < 0.02 * want,
            "t {}: ay {} vs V²/R {want}",
            rec.t,
            v.ay
        );
        let off = v.x.hypot(v.y - r) - r;
        assert!(off.abs() < 0.1, "t {}: {off} m off the circle", rec.t);
        checked += 1;
    }
    assert!(checked > 7000);
    let last = log.records.last().unwrap().vehicle;
    assert!(last.ay > 4.0, "the ramp reached {} m/s²", last.ay);
}

/// Straight coast-down with the steering wheel held straight: the left and right tyres are
/// mirror images, so the side forces cancel exactly; the car slows (drag and rolling
/// resistance) without steering away.
#[test]
fn straight_coast_down_has_no_lateral_force() {
    let mut cfg = named("coast-down");
    cfg.duration = 5.0;
    let log = run(&cfg);
    let mut last_vx = f64::INFINITY;
    for rec in &log.records {
        let v = &rec.vehicle;
        assert!(v.ay.abs() < 1e-9, "t {}: ay {}", rec.t, v.ay);
        let fy: f64 = rec.wheels.iter().map(|w| w.fy).sum();
        assert!(fy.abs() < 1e-6, "t {}: ΣFy {fy}", rec.t);
        assert!(v.vy.abs() < 1e-9 && v.r.abs() < 1e-9 && v.y.abs() < 1e-9);
        assert!(v.vx <= last_vx, "coasting never speeds up");
        last_vx = v.vx;
    }
    let first = log.records.first().unwrap().vehicle.vx;
    let decel = (first - last_vx) / 5.0;
    assert!(
        (0.1..0.6).contains(&decel),
        "coast-down deceleration {decel} m/s² (drag + rolling resistance)"
    );
}

/// Load transfer moves load between the wheels but never creates any: on a flat road the
/// four Fz sum to m·g at every step, through a sine-with-dwell that lifts a wheel nearly off.
#[test]
fn load_transfer_sums_to_the_weight() {
    let log = run(&named("sine-dwell"));
    let mut max_transfer: f64 = 0.0;
    let statics = VehicleParams::default().static_loads();
    for rec in &log.records {
        let sum: f64 = rec.wheels.iter().map(|w| w.fz).sum();
        assert!(
            (sum - log.weight).abs() < 1e-9 * log.weight,
            "t {}: ΣFz {sum} vs m·g {}",
            rec.t,
            log.weight
        );
        for (w, s) in rec.wheels.iter().zip(statics) {
            max_transfer = max_transfer.max((w.fz - s).abs());
        }
    }
    assert!(
        max_transfer > 3000.0,
        "the manoeuvre moves load: {max_transfer} N"
    );
}

/// On μ = 0.3 the sine-with-dwell saturates the tyres: peak |ay| reaches about 0.3 g and not
/// more (the 10 % margin covers the tyre's load sensitivity: lightly loaded tyres have a
/// higher μ than at FNOMIN).
#[test]
fn low_friction_caps_lateral_acceleration() {
    let mut cfg = named("sine-dwell");
    cfg.road = Road::parse("mu=0.3").unwrap();
    cfg.duration = 4.0;
    let log = run(&cfg);
    let peak = log
        .records
        .iter()
        .map(|r| r.vehicle.ay.abs())
        .fold(0.0, f64::max);
    assert!(
        (0.8 * 0.3 * G..=1.1 * 0.3 * G).contains(&peak),
        "peak |ay| {peak} m/s² on μ = 0.3"
    );
    assert!(log
        .records
        .iter()
        .all(|r| r.wheels.iter().all(|w| w.mu_true == 0.3)));
}

fn abs_split(abs: bool, driver: bool) -> Log {
    abs_split_from(25.0, abs, driver)
}

fn abs_split_from(speed: f64, abs: bool, driver: bool) -> Log {
    let mut cfg = SimConfig::new(Manoeuvre::AbsSplit {
        speed,
        brake_at: 0.3,
        decel: 1.2 * G,
        driver,
    });
    if !abs {
        cfg.abs = None;
    }
    cfg.duration = 12.0;
    run(&cfg)
}

/// Straight full braking on μ-split (left 0.9, right 0.2): the ABS keeps every wheel rolling
/// with bounded slip and stops shorter than locked wheels; the yaw moment turns the car
/// towards the high-μ side (left, r > 0) and the driver counter-steers (δ < 0).
#[test]
fn abs_on_mu_split() {
    let with = abs_split(true, true);
    let locked = abs_split(false, true);
    let stop = with.stop.expect("the ABS stop ends at standstill");
    let dist_locked = locked.stop.map_or(f64::INFINITY, |s| s.distance);
    assert!(
        stop.distance < 0.9 * dist_locked,
        "ABS {} m vs locked {dist_locked} m",
        stop.distance
    );
    // While the ABS works (after the first 0.3 s of braking, above 5 m/s) every wheel rolls,
    // and above 8 m/s the slip stays within 0.25. Below about 6 m/s this threshold ABS (no
    // wheel-deceleration logic) overshoots on the low-μ rear wheel — slip is Δv/v and grows
    // fast as v falls — to 0.3–0.5 depending on where its dump cycles fall: rounding-level
    // changes of the tyre model move them (seen over start speeds 24.5–25.5 m/s). Checked at
    // three start speeds so that the bound is not a lucky phase.
    for speed in [24.9, 25.0, 25.4] {
        let log = abs_split_from(speed, true, true);
        for rec in log
            .records
            .iter()
            .filter(|r| r.t > 0.6 && r.vehicle.vx > 5.0)
        {
            for (i, w) in rec.wheels.iter().enumerate() {
                assert!(
                    w.omega > 0.0 && (rec.vehicle.vx < 8.0 || w.kappa > -0.25),
                    "start {speed} m/s, t {}: wheel {i} slip {} omega {} at {} m/s",
                    rec.t,
                    w.kappa,
                    w.omega,
                    rec.vehicle.vx
                );
            }
        }
    }
    // Locked wheels do lock.
    assert!(locked
        .records
        .iter()
        .any(|r| r.wheels.iter().all(|w| w.omega == 0.0)));
    // The driver counter-steers to the right on average while braking.
    let steer: Vec<f64> = with
        .records
        .iter()
        .filter(|r| r.t > 0.3 && r.vehicle.vx > 5.0)
        .map(|r| r.vehicle.steer)
        .collect();
    assert!(steer.iter().sum::<f64>() / (steer.len() as f64) < 0.0);
    // Without a driver: the brake forces' yaw moment Σ −yi·Fx,i is positive on average (left
    // side brakes harder; the ABS cycles make single steps vary) and the car yaws left.
    let free = abs_split(true, false);
    let pos = VehicleParams::default().wheel_positions();
    let early: Vec<_> = free
        .records
        .iter()
        .filter(|r| r.t > 0.35 && r.t < 1.0)
        .collect();
    let mean = early
        .iter()
        .map(|rec| {
            rec.wheels
                .iter()
                .zip(pos)
                .map(|(w, (_, y))| -y * w.fx)
                .sum::<f64>()
        })
        .sum::<f64>()
        / early.len() as f64;
    assert!(mean > 1000.0, "mean brake yaw moment {mean} N·m");
    assert!(early.last().unwrap().vehicle.r > 0.05);
}

/// The fixed-step scheme converges at first order: through the sine-with-dwell the lateral
/// position at 2.5 s moves by less than a centimetre between 2, 1 and 0.5 ms, and the change
/// halves with the step.
#[test]
fn step_size_converges() {
    let y_at = |dt: f64| {
        let mut cfg = named("sine-dwell");
        cfg.dt = dt;
        cfg.duration = 2.6;
        let log = run(&cfg);
        let k = (2.5 / dt).round() as usize;
        log.records[k].vehicle.y
    };
    let (y2, y1, y05) = (y_at(2e-3), y_at(1e-3), y_at(5e-4));
    let (d21, d1h) = ((y2 - y1).abs(), (y1 - y05).abs());
    assert!(d21 < 0.01 && d1h < 0.6 * d21, "{y2} {y1} {y05}");
}

/// Same configuration, same tyre: bit-identical logs (rough road and ABS included).
#[test]
fn runs_are_deterministic() {
    let mut cfg = named("brake-in-turn");
    cfg.road = Road::parse("mu=0.8+rough=0.005@42").unwrap();
    cfg.duration = 4.0;
    let a = run(&cfg);
    let b = run(&cfg);
    assert_eq!(a, b);
    assert!(a.records.len() >= 3900);
}

/// An uneven road makes the wheel loads fluctuate about their static values; the vehicle's
/// weight is still carried on average.
#[test]
fn uneven_road_modulates_the_load() {
    let mut cfg = named("coast-down");
    cfg.road = Road::parse("uneven=0.01@2").unwrap(); // 20 m/s over 2 m: 10 Hz
    cfg.manoeuvre = Manoeuvre::CoastDown { speed: 20.0 };
    cfg.duration = 2.0;
    let log = run(&cfg);
    let recs: Vec<_> = log.records.iter().filter(|r| r.t > 1.0).collect();
    let n = recs.len() as f64;
    let mean: f64 = recs.iter().map(|r| r.wheels[0].fz).sum::<f64>() / n;
    let sd = (recs
        .iter()
        .map(|r| (r.wheels[0].fz - mean).powi(2))
        .sum::<f64>()
        / n)
        .sqrt();
    let stat = VehicleParams::default().static_loads()[0];
    assert!(sd > 0.1 * stat, "load fluctuation {sd} N");
    assert!(
        (mean - stat).abs() < 0.03 * stat,
        "mean {mean} vs static {stat}"
    );
}

/// docs/architecture.md: a road of friction μ scales the tyre so that μy at FNOMIN, γ = 0 is μ.
#[test]
fn road_friction_means_mu_y_at_fnomin() {
    let p = tyre();
    for mu in [0.2, 0.5, 1.1] {
        let v = Vehicle::new(
            VehicleParams::default(),
            &p,
            &Road::uniform(mu),
            Initial {
                speed: 10.0,
                yaw_rate: 0.0,
            },
        )
        .unwrap();
        let w = &v.wheels[0];
        let out = mf::eval::<f64, Libm>(
            &w.params,
            &Input {
                fz: p.fnomin,
                vx: p.longvl,
                p: Some(p.nompres),
                ..Input::default()
            },
            &Options::default(),
        )
        .unwrap();
        assert!((out.mu_y - mu).abs() < 1e-12, "μ {mu}: μy {}", out.mu_y);
    }
}

/// A step from dry to ice along X reaches the front wheels first, the rear ones a wheelbase
/// later.
#[test]
fn friction_steps_follow_the_wheels() {
    let mut cfg = SimConfig::new(Manoeuvre::CoastDown { speed: 20.0 });
    cfg.road = Road::parse("step=0.9@0,0.1@20").unwrap();
    cfg.duration = 1.5;
    let log = run(&cfg);
    let first_ice = |i: usize| {
        log.records
            .iter()
            .find(|r| r.wheels[i].mu_true == 0.1)
            .unwrap()
            .vehicle
            .x
    };
    let p = VehicleParams::default();
    // Front wheels at X = x + a reach 20 m when the CG is at 20 − a; the rear at 20 + b.
    assert!((first_ice(0) - (20.0 - p.a)).abs() < 0.05);
    assert!((first_ice(3) - (20.0 + p.b)).abs() < 0.05);
}

#[test]
fn road_specs() {
    let r = Road::parse("split=0.9/0.2+patch=0.1@10..20:right+uneven=0.01@3").unwrap();
    assert_eq!(r.mu(15.0, 1.0, 1.0), 0.9);
    assert_eq!(r.mu(15.0, -1.0, 1.0), 0.1);
    assert_eq!(r.mu(25.0, -1.0, 1.0), 0.2);
    assert!(!r.is_flat());
    for bad in [
        "",
        "mu",
        "mu=",
        "mu=abc",
        "mu=0",
        "mu=-0.5",
        "mu=3",
        "mu=nan",
        "mu=0.9+mu=0.5",
        "mu=0.9+split=0.9/0.2",
        "split=0.9",
        "split=0.9/",
        "step=0.9@0,0.3",
        "step=0.9@10,0.3@5",
        "patch=0.3@60..40",
        "patch=0.3@40",
        "patch=0.3@40..60:middle",
        "uneven=0.01",
        "uneven=0.5@2",
        "uneven=0.01@0",
        "rough=0.01@x",
        "rough=-1@3",
        "ice=0.1",
        "mu=0.9 + ",
    ] {
        let e = Road::parse(bad).expect_err(bad);
        assert!(!e.contains('\n'), "one-line error for '{bad}': {e}");
    }
}

fn out_dir(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("gough-sim-test-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    d
}

fn gough() -> Command {
    Command::new(gough_host_tests::gough_bin())
}

const TIR: &str = concat!(
    env!("CARGO_MANIFEST_DIR"),
    "/data/tyres/MagicFormula61_Parameters.tir"
);

#[test]
fn cli_writes_the_log_and_the_plots() {
    let dir = out_dir("ok");
    let o = gough()
        .args(["sim", "--manoeuvre", "step-steer", "--tir", TIR])
        .args(["--road", "mu=0.8", "--duration", "0.8", "--speed", "15"])
        .args(["--plot-size", "600x450", "--out"])
        .arg(&dir)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let csv = std::fs::read_to_string(dir.join("log.csv")).unwrap();
    let header: Vec<&str> = csv.lines().next().unwrap().split(',').collect();
    for col in [
        "t",
        "x",
        "y",
        "yaw",
        "vx",
        "vy",
        "r",
        "ax",
        "ay",
        "steer",
        "fl_vx",
        "fl_vsx",
        "fr_vsy",
        "rl_alpha",
        "rr_kappa",
        "fl_gamma",
        "fr_fz",
        "rl_fx",
        "rr_fy",
        "fl_mz",
        "fr_mu_true",
        "rl_omega",
        "rr_torque",
    ] {
        assert!(header.contains(&col), "column {col} missing");
    }
    assert_eq!(csv.lines().count(), 801);
    for png in ["signals.png", "gough.png"] {
        let b = std::fs::read(dir.join(png)).unwrap();
        assert_eq!(&b[..4], b"\x89PNG", "{png}");
    }
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn cli_bad_arguments_fail_in_one_line() {
    for (i, args) in [
        vec!["--manoeuvre", "drift", "--tir", TIR],
        vec!["--manoeuvre", "slalom", "--tir", TIR, "--road", "mu=abc"],
        vec!["--manoeuvre", "slalom", "--tir", TIR, "--speed", "fast"],
        vec!["--manoeuvre", "slalom", "--tir", TIR, "--dt", "0.01"],
        vec!["--manoeuvre", "slalom", "--tir", TIR, "--duration", "-1"],
        vec!["--manoeuvre", "slalom", "--tir", TIR, "--log-every", "0"],
        vec!["--manoeuvre", "slalom", "--tir", TIR, "--plot-size", "big"],
        vec!["--manoeuvre", "slalom", "--tir", "/nonexistent.tir"],
        vec!["--tir", TIR],
        vec!["--manoeuvre", "slalom"],
    ]
    .into_iter()
    .enumerate()
    {
        let dir = out_dir(&format!("bad{i}"));
        let o = gough()
            .arg("sim")
            .args(&args)
            .arg("--out")
            .arg(&dir)
            .output()
            .unwrap();
        let e = String::from_utf8_lossy(&o.stderr);
        assert!(!o.status.success(), "{args:?} should fail");
        assert_eq!(e.trim().lines().count(), 1, "{args:?}: one-line error: {e}");
        assert!(!dir.join("log.csv").exists());
    }
}
