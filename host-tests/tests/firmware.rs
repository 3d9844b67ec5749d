//! The firmware under QEMU, end to end over SLCAN/TCP. Needs `qemu-system-arm` and the release
//! firmware (`cargo build --release` in firmware/), so the tests are `#[ignore]`d in a plain
//! `cargo test`; `cargo xtask test-all` builds the firmware and runs them with `--ignored`
//! (and fails, never skips, when QEMU is missing).
use gough::proto::{
    AckCode, Command, CompactMeasurement, Key, MacLen, Measurement, Msg, MsgType, Mtu, Policy,
    Segmenter, Settings, Signer, Wheel,
};
use gough_host::device::{self, Device, Qemu, SlcanTcp};
use std::path::Path;
use std::process::Command as Proc;
use std::time::Duration;

fn root() -> &'static Path {
    Path::new(concat!(env!("CARGO_MANIFEST_DIR"), "/.."))
}

/// The TEST KEY (`firmware/keys/test.key`).
fn test_key_file() -> std::path::PathBuf {
    root().join("firmware/keys/test.key")
}

fn test_key() -> Key {
    device::read_key(&test_key_file()).unwrap()
}

/// The firmware under QEMU in `target/WORKDIR`, provisioned with the test key (8-byte MACs), and
/// a client that signs with it.
fn keyed(workdir: &str) -> (Qemu, Device) {
    keyed_with(workdir, Policy::StateChanging)
}

/// As [`keyed`], the device provisioned with `policy`; under [`Policy::All`] the client signs
/// everything and checks every answer.
fn keyed_with(workdir: &str, policy: Policy) -> (Qemu, Device) {
    let q = Qemu::start_keyed(
        &device::firmware_elf("gough-firmware"),
        &root().join("target").join(workdir),
        true,
        None,
        Some((&test_key(), MacLen::DEFAULT, policy)),
    )
    .unwrap();
    let mut dev = Device::new(SlcanTcp::connect(q.port, Duration::from_secs(20)).unwrap());
    match policy {
        Policy::StateChanging => dev.authenticate(test_key()).unwrap(),
        Policy::All => dev.authenticate_all(test_key()).unwrap(),
    }
    (q, dev)
}

/// `gough replay --no-build --key-file TEST_KEY ARGS --tir TIR --log LOG --out OUT --workdir target/WORKDIR`.
fn replay(
    args: &[&str],
    tir: &Path,
    log: &Path,
    out: &Path,
    workdir: &str,
) -> std::process::Output {
    Proc::new(gough_host_tests::gough_bin())
        .args(["replay", "--no-build", "--key-file"])
        .arg(test_key_file())
        .args(args)
        .arg("--tir")
        .arg(tir)
        .arg("--log")
        .arg(log)
        .arg("--out")
        .arg(out)
        .arg("--workdir")
        .arg(root().join("target").join(workdir))
        .output()
        .unwrap()
}

/// With every message authenticated (`--secure-all`: the measurements signed, every answer
/// checked); the preview test below replays with the state-changing messages signed only.
#[test]
#[ignore = "needs QEMU and the release firmware; run by `cargo xtask test-all`"]
fn replay_answers_equal_the_host_f32_run() {
    let out = std::env::temp_dir().join(format!("gough-replay-{}.csv", std::process::id()));
    let o = replay(
        &["--check", "--secure-all"],
        &root().join("host-tests/data/tyres/MagicFormula61_Parameters.tir"),
        &root().join("examples/replay_log.csv"),
        &out,
        "qemu-replay",
    );
    let err = String::from_utf8_lossy(&o.stderr);
    eprintln!("{err}");
    assert!(o.status.success(), "gough replay failed");
    assert!(err.contains(
        "check: device answers = host f32 run (math::Fast): forces worst 0 ulp; estimates worst 0 ulp (200 rows)"
    ));
    assert!(err.contains("dropped 0"));
    // 200 forces, 200 estimates, the upload's acks and statuses: every one verified.
    assert!(
        err.contains("refused 0 (unsigned 0, bad MAC 0, stale 0); device refused: unsigned 0, bad MAC 0, stale 0"),
        "answers not all checked"
    );
    let verified: u32 = err
        .split("answers checked: ")
        .nth(1)
        .and_then(|r| r.split(' ').next())
        .and_then(|n| n.parse().ok())
        .unwrap();
    assert!(verified >= 400, "{verified} answers verified");
    let res = std::fs::read_to_string(&out).unwrap();
    let mut lines = res.lines();
    assert_eq!(
        lines.next(),
        Some("t,wheel,fx,fy,mz,flags,ack,mu,sigma,state,mu_min,change")
    );
    let rows: Vec<Vec<&str>> = lines.map(|l| l.split(',').collect()).collect();
    assert_eq!(rows.len(), 200);
    // Every row has forces and an estimate; the slalom is identifiable part of the time, and
    // then reads the tyre's own surface (μy0 = 1.018 for this file).
    let mut identifiable = 0;
    for r in &rows {
        assert_eq!(r.len(), 12, "{r:?}");
        assert!(r[2].parse::<f32>().is_ok() && r[6].is_empty(), "{r:?}");
        let (mu, sigma): (f32, f32) = (r[7].parse().unwrap(), r[8].parse().unwrap());
        let mu_min: f32 = r[10].parse().unwrap();
        assert!(mu > 0.0 && sigma > 0.0, "{r:?}");
        // A lower bound on the grid of surfaces (0.05 ..= 1.25·μy0).
        assert!((0.05..=1.25 * 1.018 + 1e-3).contains(&mu_min), "{r:?}");
        // One surface throughout: no change is declared.
        assert_eq!(r[11], "0", "{r:?}");
        match r[9] {
            "identifiable" => {
                identifiable += 1;
                assert!((mu - 1.018).abs() < 0.1, "{r:?}");
            }
            "not_identifiable" | "fallback" => {}
            s => panic!("state {s}"),
        }
    }
    // How many depends on the estimator's gates (src/mu); that it identifies at all does not.
    assert!(identifiable > 0, "no identifiable row");
}

#[test]
#[ignore = "needs QEMU and the release firmware; run by `cargo xtask test-all`"]
fn garbage_on_the_uart_is_counted_and_harmless_and_a_device_without_a_key_refuses_changes() {
    let mut q = Qemu::start(
        &device::firmware_elf("gough-firmware"),
        &root().join("target/qemu-garbage"),
        true,
        None,
    )
    .unwrap();
    let mut dev = Device::new(SlcanTcp::connect(q.port, Duration::from_secs(20)).unwrap());
    let before = dev.status(Duration::from_secs(10)).unwrap();
    // Random bytes, overlong lines, bad hex, frames on our identifiers with random payloads.
    let mut x = 0x9e37_79b9u32;
    let mut rnd = || {
        x ^= x << 13;
        x ^= x >> 17;
        x ^= x << 5;
        x
    };
    let mut junk = Vec::new();
    for _ in 0..3000 {
        junk.push(rnd() as u8);
    }
    junk.extend_from_slice(b"\rtZZZ8\rt3008\rt3001\rt301FFF\r");
    for _ in 0..200 {
        let id = if rnd() % 2 == 0 { 0x300 } else { 0x301 };
        let n = (rnd() % 9) as usize;
        let mut l = format!("t{id:03X}{n}");
        for _ in 0..n {
            l.push_str(&format!("{:02X}", rnd() as u8));
        }
        l.push('\r');
        junk.extend_from_slice(l.as_bytes());
    }
    junk.extend_from_slice(b"\r");
    dev.link.write_raw(&junk).unwrap();
    // The device still answers a good measurement correctly.
    let m = Measurement {
        wheel: Wheel::RearLeft,
        t_us: 42,
        fz: 5000.0,
        alpha: Some(0.03),
        vx: Some(20.0),
        ..Measurement::default()
    };
    dev.send(&Msg::Measurement(m)).unwrap();
    let ans = loop {
        match dev.recv(Duration::from_secs(10)).unwrap() {
            Msg::Forces(f) => break f,
            _ => continue,
        }
    };
    assert_eq!((ans.wheel, ans.t_us), (Wheel::RearLeft, 42));
    let after = dev.status(Duration::from_secs(10)).unwrap();
    eprintln!("before {before:?}\nafter {after:?}");
    assert!(
        after.link_errors > before.link_errors,
        "bad SLCAN lines are counted"
    );
    assert!(
        after.rx.dropped() > before.rx.dropped(),
        "bad frames are counted"
    );
    assert!(after.rx.frames >= before.rx.frames + 200);
    // This device was started without a key: it refuses every state-changing message, signed
    // (with the test key) or not, and counts them; it keeps running (Stop refused too).
    assert_eq!(after.auth.mac_len, 0);
    assert!(dev.authenticate(test_key()).is_err(), "no key to sign for");
    dev.signer = Some(Signer::new(
        test_key(),
        MacLen::DEFAULT,
        after.auth.epoch,
        0,
    ));
    let settings = Msg::Settings(Settings {
        wheelbase: 2.9,
        ..Settings::default()
    });
    for signed in [true, false] {
        if !signed {
            dev.signer = None;
        }
        dev.send(&settings).unwrap();
        let a = dev.wait_ack(MsgType::Settings, Duration::from_secs(10));
        assert_eq!(a.unwrap(), AckCode::NoKey, "signed {signed}");
        dev.send(&Msg::Command(Command::Stop)).unwrap();
        let a = dev.wait_ack(MsgType::Command, Duration::from_secs(10));
        assert_eq!(a.unwrap(), AckCode::NoKey, "signed {signed}");
    }
    let st = dev.status(Duration::from_secs(10)).unwrap();
    assert_eq!((st.auth.no_key, st.auth.accepted), (4, 0), "{:?}", st.auth);
    assert_eq!(q.wait(Duration::from_millis(200)), None, "still running");
}

#[test]
#[ignore = "needs QEMU and the release firmware; run by `cargo xtask test-all`"]
fn compact_measurement_is_answered_like_the_measurement_it_stands_for() {
    let (mut q, mut dev) = keyed("qemu-compact");
    let m = Measurement {
        wheel: Wheel::FrontRight,
        t_us: 7,
        fz: 4321.3,
        fy: -1234.4,
        mz: 21.37,
        alpha: Some(0.0312),
        kappa: Some(-0.0207),
        vx: Some(19.99),
        ..Measurement::default()
    };
    let c = CompactMeasurement::new(&m).unwrap();
    let forces = |dev: &mut Device, msg: Msg| {
        dev.send(&msg).unwrap();
        loop {
            match dev.recv(Duration::from_secs(10)).unwrap() {
                Msg::Forces(f) => break f,
                _ => continue,
            }
        }
    };
    let a = forces(&mut dev, Msg::CompactMeasurement(c));
    let b = forces(&mut dev, Msg::Measurement(c.measurement()));
    let raw = forces(&mut dev, Msg::Measurement(m));
    assert_eq!((a.wheel, a.t_us), (Wheel::FrontRight, 7));
    assert_eq!((a.fx, a.fy, a.mz, a.flags), (b.fx, b.fy, b.mz, b.flags));
    // Within the rounding of the counts (α, κ to 0.5e-4): a few newtons.
    assert!(
        (a.fy - raw.fy).abs() < 10.0 && (a.fx - raw.fx).abs() < 10.0,
        "{a:?} {raw:?}"
    );
    assert!(a.fy != 0.0);
    let st = dev.status(Duration::from_secs(10)).unwrap();
    assert_eq!(st.rx.dropped(), 0);
    dev.send(&Msg::Command(Command::Stop)).unwrap();
    assert_eq!(q.wait(Duration::from_secs(20)), Some(0));
}

/// A car's four wheels in a slalom with braking (rows interleaved FL, FR, RL, RR at 50 Hz per
/// wheel, the rear wheels at 60 % of the fronts' slip angle), "measured" = the f64 Magic
/// Formula; returns the log's text.
fn car_log(p: &gough::mf::Params<f64>, seconds: f64) -> String {
    use gough::math::Libm;
    use gough::mf::{self, Input, Options};
    use std::fmt::Write as _;
    let tau = std::f64::consts::TAU;
    let mut s = String::from("t,wheel,fz,fy,mz,fx,vx,alpha,kappa,gamma\n");
    for i in 0..(seconds * 50.0) as usize {
        let t = i as f64 * 0.02;
        for wheel in 0..4 {
            let side = if wheel % 2 == 0 { 1.0 } else { -1.0 };
            let rear = if wheel >= 2 { 0.6 } else { 1.0 };
            let fz = (6000.0 * (1.0 + 0.25 * side * (tau * 0.5 * t).sin())).round();
            let alpha = (rear * 0.12 * (tau * 0.5 * t).sin() * 1e6).round() / 1e6;
            let kappa = ((-0.08 * (tau * 0.25 * t).sin().powi(2)) * 1e6).round() / 1e6;
            let vx = 20.0 - 2.0 * t;
            let input = Input {
                fz,
                kappa,
                alpha,
                gamma: 0.0,
                phit: 0.0,
                vx,
                p: None,
            };
            let o = mf::eval::<f64, Libm>(p, &input, &Options::default()).unwrap();
            writeln!(
                s,
                "{t:.2},{wheel},{fz:.0},{:.1},{:.2},{:.1},{vx:.2},{alpha:.6},{kappa:.6},0",
                o.fy, o.mz, o.fx
            )
            .unwrap();
        }
    }
    s
}

#[test]
#[ignore = "needs QEMU and the release firmware; run by `cargo xtask test-all`"]
fn the_device_runs_the_front_to_rear_preview_the_settings_ask_for_as_the_host_does() {
    use gough::proto::Settings;
    use gough_host::replay::{self, Backend32};
    let tir = root().join("host-tests/data/tyres/MagicFormula61_Parameters.tir");
    let p = gough_host::tyre::load(&tir).unwrap().params;
    let dir = std::env::temp_dir().join(format!("gough-replay-car-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let log_path = dir.join("car.csv");
    std::fs::write(&log_path, car_log(&p, 3.0)).unwrap();
    // On the host first: the preview hands the fronts' readings over and changes the rear
    // wheels' estimates, never the fronts'.
    let log = replay::read_log(&log_path).unwrap();
    let p32 = p.cast::<f32>();
    let host = |wheelbase: f32| {
        let s = Settings {
            wheelbase,
            ..Settings::default()
        };
        replay::host_f32(&p32, &s, &log, Backend32::Fast).unwrap()
    };
    let (alone, told) = (host(0.0), host(2.9));
    let mut rear_differs = 0;
    for ((a, b), m) in alone.iter().zip(&told).zip(&log) {
        if m.wheel.index() < 2 {
            assert_eq!(a, b);
        } else {
            rear_differs += usize::from(a != b);
        }
    }
    assert!(rear_differs > 0, "the preview changed no rear estimate");
    assert!(replay::host_f32(
        &p32,
        &Settings {
            wheelbase: -1.0,
            ..Settings::default()
        },
        &log,
        Backend32::Fast
    )
    .is_err());
    // The device, told the wheelbase in its settings, answers the host's run to the bit.
    let out = dir.join("car-results.csv");
    let o = replay(
        &["--check", "--wheelbase", "2.9"],
        &tir,
        &log_path,
        &out,
        "qemu-replay-car",
    );
    let err = String::from_utf8_lossy(&o.stderr);
    eprintln!("{err}");
    assert!(o.status.success(), "gough replay failed");
    assert!(err.contains("settings: wheelbase 2.9 m (front-to-rear preview)"));
    assert!(err.contains(&format!(
        "check: device answers = host f32 run (math::Fast): forces worst 0 ulp; estimates worst 0 ulp ({} rows)",
        log.len()
    )));
    // A wheelbase the device refuses: the replay stops before streaming.
    let o = replay(
        &["--wheelbase", "-2.9"],
        &tir,
        &log_path,
        &out,
        "qemu-replay-car",
    );
    assert!(!o.status.success());
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        err.contains("--wheelbase -2.9: not a positive number"),
        "{err}"
    );
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
#[ignore = "needs QEMU and the release firmware; run by `cargo xtask test-all`"]
fn a_wheelbase_out_of_range_is_refused_and_unsigned_forged_or_replayed_changes_too() {
    let (mut q, mut dev) = keyed("qemu-settings");
    let ack = |dev: &mut Device, s: Settings| {
        dev.send(&Msg::Settings(s)).unwrap();
        dev.wait_ack(MsgType::Settings, Duration::from_secs(10))
            .unwrap()
    };
    for (wheelbase, want) in [
        (2.9, AckCode::Ok),
        (0.0, AckCode::Ok),
        (-2.9, AckCode::BadSettings),
        (f32::NAN, AckCode::BadSettings),
        (f32::INFINITY, AckCode::BadSettings),
        (3.1, AckCode::Ok),
    ] {
        let s = Settings {
            wheelbase,
            ..Settings::default()
        };
        assert_eq!(ack(&mut dev, s), want, "wheelbase {wheelbase}");
    }
    let st = dev.status(Duration::from_secs(10)).unwrap();
    assert_eq!(st.rx.dropped(), 0);
    assert_eq!(
        (st.auth.mac_len, st.auth.accepted, st.auth.counter),
        (8, 6, 6)
    );
    let s = Settings::default();
    // Unsigned.
    let signer = dev.signer.take().unwrap();
    assert_eq!(ack(&mut dev, s), AckCode::MacMissing);
    // Forged: another key (the freshness right).
    let (epoch, counter) = signer.freshness();
    dev.signer = Some(Signer::new(
        Key::new([0x5a; 16]),
        MacLen::DEFAULT,
        epoch,
        counter,
    ));
    assert_eq!(ack(&mut dev, s), AckCode::BadMac);
    // A 4-byte MAC where the device expects 8.
    dev.signer = Some(Signer::new(
        test_key(),
        MacLen::new(4).unwrap(),
        epoch,
        counter,
    ));
    assert_eq!(ack(&mut dev, s), AckCode::BadMac);
    // Replayed: the same secured message (same counter, same MAC) twice.
    dev.signer = Some(signer.clone());
    assert_eq!(ack(&mut dev, s), AckCode::Ok);
    dev.signer = Some(signer.clone());
    assert_eq!(ack(&mut dev, s), AckCode::StaleFreshness);
    // A replayed upload (a short text, refused by the parser at its commit, so every message
    // of it was accepted): refused at its first message; the parameters in use stay.
    let text = b"[MODEL]\nFITTYP = 61\nFNOMIN = oops\n";
    let hash = st.param_hash;
    let before = dev.signer.clone().unwrap();
    let e = dev.upload_tir(text).unwrap_err();
    assert!(e.contains("line 3"), "{e}");
    let after = dev.signer.clone().unwrap();
    dev.signer = Some(before);
    let e = dev.upload_tir(text).unwrap_err();
    assert!(e.contains("StaleFreshness"), "{e}");
    dev.signer = Some(after);
    let st = dev.status(Duration::from_secs(10)).unwrap();
    assert_eq!(st.param_hash, hash);
    assert_eq!(
        (st.auth.missing, st.auth.bad_mac, st.auth.stale),
        (1, 2, 2),
        "{:?}",
        st.auth
    );
    // A replayed command: Reset accepted (the device restarts: its next epoch, from the
    // non-volatile boot counter), then the same Reset again: its MAC belongs to the old epoch.
    let pre_reset = dev.signer.clone().unwrap();
    dev.send(&Msg::Command(Command::Reset)).unwrap();
    assert_eq!(
        dev.wait_ack(MsgType::Command, Duration::from_secs(10))
            .unwrap(),
        AckCode::Ok
    );
    std::thread::sleep(Duration::from_millis(300));
    dev.authenticate(test_key()).unwrap();
    let st = dev.status(Duration::from_secs(10)).unwrap();
    assert_eq!(st.auth.epoch, epoch + 1, "{:?}", st.auth);
    dev.signer = Some(pre_reset);
    dev.send(&Msg::Command(Command::Reset)).unwrap();
    assert_eq!(
        dev.wait_ack(MsgType::Command, Duration::from_secs(10))
            .unwrap(),
        AckCode::BadMac
    );
    dev.authenticate(test_key()).unwrap();
    dev.send(&Msg::Command(Command::Stop)).unwrap();
    assert_eq!(q.wait(Duration::from_secs(20)), Some(0));
}

/// Provisioned with `--secure-all`: a measurement not signed, forged (another key) or replayed is
/// refused, counted by reason and not answered (the next answer is the next good measurement's);
/// a measurement and a settings message whose frames interleave on the bus (the settings,
/// signed later, complete first) are both accepted: freshness per identifier.
#[test]
#[ignore = "needs QEMU and the release firmware; run by `cargo xtask test-all`"]
fn with_every_message_authenticated_bad_measurements_are_refused_unanswered_and_counted() {
    use embedded_can::blocking::Can as _;
    use embedded_can::{Frame as _, StandardId};
    let (mut q, mut dev) = keyed_with("qemu-secure-all", Policy::All);
    let m = |t_us: u32| {
        Msg::Measurement(Measurement {
            wheel: Wheel::FrontLeft,
            t_us,
            fz: 4000.0,
            alpha: Some(0.02),
            kappa: Some(0.01),
            vx: Some(20.0),
            ..Measurement::default()
        })
    };
    // The next Forces' sample time; anything else before it must be an Estimate or a
    // Calibration report (no Ack, no Forces of a refused measurement).
    let forces_t = |dev: &mut Device| loop {
        match dev.recv(Duration::from_secs(10)).unwrap() {
            Msg::Forces(f) => break f.t_us,
            Msg::Estimate(_) | Msg::Calibration(_) => continue,
            other => panic!("unexpected answer {other:?}"),
        }
    };
    dev.send(&m(1)).unwrap();
    assert_eq!(forces_t(&mut dev), 1);
    let good = dev.signer.clone().unwrap();
    let (epoch, counter) = good.freshness();
    // Unsigned, then signed by another key, then replayed (counter 2 again): none answered.
    dev.signer = None;
    dev.send(&m(100)).unwrap();
    dev.signer = Some(Signer::new(
        Key::new([0x5a; 16]),
        MacLen::DEFAULT,
        epoch,
        counter,
    ));
    dev.send(&m(101)).unwrap();
    dev.signer = Some(good.clone());
    dev.send(&m(2)).unwrap();
    dev.signer = Some(good);
    dev.send(&m(102)).unwrap();
    dev.send(&m(3)).unwrap();
    assert_eq!(forces_t(&mut dev), 2);
    assert_eq!(forces_t(&mut dev), 3);
    // Interleaved: the measurement's first frame, the settings' frames, the measurement's rest.
    let s = dev.signer.as_mut().unwrap();
    let mut meas = Segmenter::sealed(&m(4), 0x70, Mtu::Classic, s).unwrap();
    let settings = Msg::Settings(Settings::default());
    let mut cfg = Segmenter::sealed(&settings, 0x71, Mtu::Classic, s).unwrap();
    let send_frames = |dev: &mut Device, cid: u16, seg: &mut Segmenter, n: usize| {
        let mut buf = [0u8; 64];
        for _ in 0..n {
            let Some(d) = seg.next_frame(&mut buf) else {
                break;
            };
            let f = gough::proto::slcan::CanFrame::new(StandardId::new(cid).unwrap(), d).unwrap();
            dev.link.transmit(&f).unwrap();
        }
    };
    send_frames(&mut dev, gough::proto::id::MEASUREMENT, &mut meas, 1);
    send_frames(&mut dev, gough::proto::id::CONFIG, &mut cfg, usize::MAX);
    send_frames(
        &mut dev,
        gough::proto::id::MEASUREMENT,
        &mut meas,
        usize::MAX,
    );
    assert_eq!(
        dev.wait_ack(MsgType::Settings, Duration::from_secs(10))
            .unwrap(),
        AckCode::Ok
    );
    assert_eq!(forces_t(&mut dev), 4);
    let st = dev.status(Duration::from_secs(10)).unwrap();
    assert_eq!(
        (st.auth.missing, st.auth.bad_mac, st.auth.stale),
        (1, 1, 1),
        "{:?}",
        st.auth
    );
    assert_eq!(st.rx.dropped(), 0);
    // Every answer verified (forces, ack, statuses), none refused.
    let a = *dev.answers.as_ref().unwrap().status();
    assert_eq!((a.missing, a.bad_mac, a.stale), (0, 0, 0), "{a:?}");
    assert!(a.accepted >= 6, "{a:?}");
    // A tool that would sign the state-changing messages only is told what the device wants.
    let e = dev.authenticate(test_key()).unwrap_err();
    assert!(e.contains("--secure-all"), "{e}");
    dev.authenticate_all(test_key()).unwrap();
    dev.send(&Msg::Command(Command::Stop)).unwrap();
    assert_eq!(q.wait(Duration::from_secs(20)), Some(0));
}
