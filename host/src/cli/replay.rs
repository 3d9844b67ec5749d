//! `gough replay`: a measurement log streamed to the firmware, its answers recorded and checked.
use super::firmware::{start, RunArgs};
use crate::device::{Device, SlcanTcp};
use crate::replay::{self, Answer, Backend32};
use crate::tyre;
use clap::Args;
use gough::mu::State;
use gough::proto::{AckCode, Msg, MsgType, Settings};
use std::path::PathBuf;
use std::time::{Duration, Instant};

/// `gough replay`
#[derive(Args)]
pub struct ReplayArgs {
    /// Tyre property file uploaded to the device (the device parses and checks it).
    #[arg(long)]
    pub tir: PathBuf,
    /// Measurement log: t,fz,fy,mz required; fx,vx,alpha,kappa,gamma,wheel optional (SI, rad, ISO-W).
    #[arg(long)]
    pub log: PathBuf,
    /// Results: t,wheel,fx,fy,mz,flags,ack,mu,sigma,state,mu_min,change.
    #[arg(long)]
    pub out: PathBuf,
    /// Talk to a firmware already listening on this TCP port instead of starting one.
    #[arg(long)]
    pub connect: Option<u16>,
    /// Measurements in flight at once.
    #[arg(long, default_value_t = 8)]
    pub window: usize,
    /// Compare every answer with the host's f32 run of the same core; fail on any difference
    /// beyond `--max-ulps`.
    #[arg(long)]
    pub check: bool,
    /// Allowed difference for `--check`, in units in the last place of f32.
    #[arg(long, default_value_t = 0)]
    pub max_ulps: u64,
    /// The car's wheelbase \[m\], sent to the device in its `Settings` after the upload: the
    /// rear wheels' estimators get the front-to-rear preview (`--check` runs the same). Without
    /// it no settings are sent (the device's defaults: every wheel alone).
    #[arg(long, value_name = "M", allow_negative_numbers = true)]
    pub wheelbase: Option<f32>,
    /// Math backend the firmware was built with, for `--check` (the default build: fast).
    #[arg(long, value_enum, default_value_t = Backend32::Fast)]
    pub backend: Backend32,
    #[command(flatten)]
    #[allow(missing_docs)]
    pub run: RunArgs,
}

/// `gough replay`
pub fn run(a: ReplayArgs) -> Result<(), String> {
    let settings = Settings {
        wheelbase: a.wheelbase.unwrap_or(0.0),
        ..Settings::default()
    };
    if a.wheelbase.is_some() && !matches!(settings.wheelbase(), Ok(Some(_))) {
        return Err(format!(
            "--wheelbase {}: not a positive number",
            settings.wheelbase
        ));
    }
    let t = tyre::load(&a.tir)?;
    let text = std::fs::read(&a.tir).map_err(|e| format!("{}: {e}", a.tir.display()))?;
    let log = replay::read_log(&a.log).map_err(|e| e.to_string())?;
    let mut qemu = None;
    let port = match a.connect {
        Some(p) => p,
        None => {
            let q = start(&a.run)?;
            let p = q.port;
            qemu = Some(q);
            p
        }
    };
    let t0 = Instant::now();
    let mut dev = Device::new(SlcanTcp::connect(port, Duration::from_secs(20))?);
    let s = dev.status(Duration::from_secs(20))?;
    eprintln!(
        "device: firmware {}.{}.{}, protocol v{}, parameters {:?} {:08x}",
        s.firmware[0], s.firmware[1], s.firmware[2], s.proto, s.source, s.param_hash
    );
    match a.run.key_file.as_deref() {
        Some(k) => {
            let key = crate::device::read_key(k)?;
            if a.run.secure_all {
                dev.authenticate_all(key)?;
                eprintln!("--secure-all: measurements signed, every answer checked");
            } else {
                dev.authenticate(key)?;
            }
            let s = dev
                .signer
                .as_ref()
                .map(|s| s.freshness())
                .unwrap_or_default();
            eprintln!(
                "signing with {} (device epoch {}, counter {})",
                k.display(),
                s.0,
                s.1
            );
        }
        None => eprintln!("no --key-file: the upload goes unsigned (a device refuses it)"),
    }
    let hash = dev.upload_tir(&text)?;
    eprintln!(
        "uploaded {} ({} bytes, crc32 {hash:08x}) in {:.2} s",
        a.tir.display(),
        text.len(),
        t0.elapsed().as_secs_f64()
    );
    if a.wheelbase.is_some() {
        dev.send(&Msg::Settings(settings))?;
        match dev.wait_ack(MsgType::Settings, Duration::from_secs(20))? {
            AckCode::Ok => eprintln!(
                "settings: wheelbase {} m (front-to-rear preview)",
                settings.wheelbase
            ),
            c => return Err(format!("the device refused the settings: {c:?}")),
        }
    }
    let t1 = Instant::now();
    let got = replay::stream(&mut dev, &log, a.window)?;
    let n_forces = got
        .iter()
        .filter(|g| matches!(g.answer, Answer::Forces(_)))
        .count();
    let n_est = got.iter().filter(|g| g.estimate.is_some()).count();
    let n_ident = got
        .iter()
        .filter(|g| matches!(g.estimate, Some(e) if e.state == State::Identifiable))
        .count();
    eprintln!(
        "{} rows -> {} forces, {} without; {} estimates, {} identifiable ({:.2} s)",
        log.len(),
        n_forces,
        log.len() - n_forces,
        n_est,
        n_ident,
        t1.elapsed().as_secs_f64()
    );
    replay::write_results(&a.out, &log, &got)
        .map_err(|e| format!("{}: cannot write: {e}", a.out.display()))?;
    let status = if qemu.is_some() {
        dev.stop(Duration::from_secs(20))?
    } else {
        dev.status(Duration::from_secs(20))?
    };
    eprintln!(
        "device counters: rx frames {} messages {} dropped {} duplicates {}; link errors {}; eval errors {}; tx {}; stack peak {} bytes",
        status.rx.frames,
        status.rx.messages,
        status.rx.dropped(),
        status.rx.duplicates,
        status.link_errors,
        status.eval_errors,
        status.tx_messages,
        status.stack_peak
    );
    if let Some(mut q) = qemu {
        match q.wait(Duration::from_secs(20)) {
            Some(0) => {}
            c => return Err(format!("firmware exit code {c:?}, expected 0")),
        }
    }
    if let Some(v) = dev.answers.as_ref() {
        let s = v.status();
        let refused = s.missing + s.bad_mac + s.stale;
        eprintln!(
            "answers checked: {} verified; refused {refused} (unsigned {}, bad MAC {}, stale {}); device refused: unsigned {}, bad MAC {}, stale {}",
            s.accepted, s.missing, s.bad_mac, s.stale,
            status.auth.missing, status.auth.bad_mac, status.auth.stale
        );
        if refused > 0 {
            return Err(format!("{refused} answers did not verify (not used)"));
        }
    }
    if a.check {
        let p32 = t.params.cast::<f32>();
        let host = replay::host_f32(&p32, &settings, &log, a.backend)?;
        let w = replay::compare(&host, &got)?;
        eprintln!(
            "check: device answers = host f32 run ({}): forces worst {} ulp; estimates worst {} ulp ({} rows)",
            a.backend.name(),
            w.forces,
            w.estimates,
            w.n_estimates
        );
        let worst = w.forces.max(w.estimates);
        if worst > a.max_ulps {
            return Err(format!(
                "device and host f32 differ by {worst} ulp (allowed {})",
                a.max_ulps
            ));
        }
    }
    Ok(())
}
