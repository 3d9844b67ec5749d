//! `gough proto ...`: the CAN protocol's description, its frames, and its bus load.
use crate::replay::{self, Answer, Backend32};
use crate::tyre;
use clap::Subcommand;
use gough::proto::{
    auth, id, Ack, CompactBatch, CompactMeasurement, CompactResults, CompactWheelResult, Feed,
    MacLen, Msg, MsgType, Mtu, Policy, Reassembler, Segmenter, Settings, Signer, Verifier, MSG_BUF,
};
use std::fmt::Write as _;
use std::path::PathBuf;

/// `gough proto ...`
#[derive(Subcommand)]
pub enum ProtoCmd {
    /// Print the DBC description of the bus (identifiers, frame header, message types).
    Dbc {
        /// Describe the CAN FD bus (64-byte frames; `Forces` and `Estimate` as physical
        /// signals) instead of classic CAN.
        #[arg(long)]
        fd: bool,
        /// MAC length of the secured messages \[bytes, 4..=8\] (as provisioned on the device).
        #[arg(long, default_value_t = 8, value_parser = clap::value_parser!(u8).range(4..=8))]
        mac_len: u8,
        /// For a device that authenticates every message (`gough firmware run --secure-all`):
        /// every identifier's message types also secured (type | 0x40).
        #[arg(long)]
        secure_all: bool,
        /// Write to this file instead of stdout.
        #[arg(long)]
        out: Option<PathBuf>,
    },
    /// The frames of a replay as the bus carries them: each measurement of a log, and the
    /// forces (or acknowledgement) and estimate the device's pipeline answers (run on the host
    /// in f32, as `gough replay --check` does), then each wheel's calibration after the log as
    /// the device reports it (`Calibration`) and as a host sends it back (`SetCalibration`;
    /// not with `--batch`). One JSON object per message: identifier,
    /// frames (hex), the encoded message (hex) and the message as the host's reassembler
    /// decodes it from those frames.
    Frames {
        /// Tyre property file.
        #[arg(long)]
        tir: PathBuf,
        /// Measurement log (as for `gough replay`).
        #[arg(long)]
        log: PathBuf,
        /// CAN FD frames instead of classic CAN.
        #[arg(long)]
        fd: bool,
        /// Send each measurement as a `CompactMeasurement` (the pipeline then runs on the
        /// values it carries).
        #[arg(long)]
        compact: bool,
        /// Send the wheels of each sample time (consecutive rows with one time, one row per
        /// wheel) as one four-wheel `CompactBatch`, answered by one `CompactResults`.
        #[arg(long, conflicts_with = "compact")]
        batch: bool,
        /// Secure the state-changing messages (the `SetCalibration`s) with this key file, as
        /// the device's owner sends them (8-byte MACs, epoch 1 from counter 1).
        #[arg(long, value_name = "KEY")]
        key_file: Option<PathBuf>,
        /// With `--key-file`: every message secured, as on a bus whose device authenticates
        /// every message (`gough firmware run --secure-all`): the measurements by the owner's
        /// signer, the answers by the device's (its own counter, epoch 1).
        #[arg(long, requires = "key_file")]
        secure_all: bool,
        /// Write to this file instead of stdout.
        #[arg(long)]
        out: Option<PathBuf>,
    },
    /// Bus load of four wheels streaming measurements and their results: frames per second and
    /// load for classic CAN and CAN FD at 100, 500 and 1000 Hz, from the real frames (the
    /// segmenter's) with worst-case bit stuffing.
    Load {
        /// Print the table as Markdown (docs/protocol.md).
        #[arg(long)]
        markdown: bool,
        /// Every message secured with MACs of this many bytes (4..=8): the cost of
        /// authenticating measurements and answers too (docs/protocol.md, "Security").
        #[arg(long, value_name = "BYTES", value_parser = clap::value_parser!(u8).range(4..=8))]
        auth_mac_len: Option<u8>,
    },
}

fn emit(s: &str, out: Option<PathBuf>) -> Result<(), String> {
    match out {
        Some(p) => std::fs::write(&p, s).map_err(|e| format!("{}: {e}", p.display())),
        None => {
            print!("{s}");
            Ok(())
        }
    }
}

/// `gough proto ...`
pub fn run(cmd: ProtoCmd) -> Result<(), String> {
    match cmd {
        ProtoCmd::Dbc {
            fd,
            mac_len,
            secure_all,
            out,
        } => {
            let mtu = if fd { Mtu::Fd } else { Mtu::Classic };
            let mac_len = MacLen::new(mac_len).ok_or("--mac-len: 4..=8")?;
            let policy = if secure_all {
                Policy::All
            } else {
                Policy::StateChanging
            };
            let mut s = String::new();
            gough::proto::dbc::write_policy(&mut s, mtu, mac_len, policy)
                .map_err(|e| e.to_string())?;
            emit(&s, out)
        }
        ProtoCmd::Frames {
            tir,
            log,
            fd,
            compact,
            batch,
            key_file,
            secure_all,
            out,
        } => {
            let key = key_file
                .as_deref()
                .map(crate::device::read_key)
                .transpose()?;
            let mut signer = key.map(|k| Signer::new(k, MacLen::DEFAULT, 1, 0));
            // The device's end under `--secure-all`: it secures its answers.
            let mut device = key
                .filter(|_| secure_all)
                .map(|k| Verifier::new(k, MacLen::DEFAULT, 1).with_policy(Policy::All));
            let t = tyre::load(&tir)?;
            let mut rows = replay::read_log(&log).map_err(|e| e.to_string())?;
            let mut sent: Vec<Msg> = rows.iter().map(|m| Msg::Measurement(*m)).collect();
            if compact {
                for (i, (m, s)) in rows.iter_mut().zip(&mut sent).enumerate() {
                    let c = CompactMeasurement::new(m).ok_or_else(|| {
                        format!(
                            "row {}: a value out of the compact measurement's range",
                            i + 1
                        )
                    })?;
                    *m = c.measurement();
                    *s = Msg::CompactMeasurement(c);
                }
            }
            let mtu = if fd { Mtu::Fd } else { Mtu::Classic };
            let mut msgs = Vec::new();
            if batch {
                batches(&t.params.cast::<f32>(), &rows, &mut msgs)?;
                sent.clear();
            }
            let (replies, cals) = replay::host_f32_calibrated(
                &t.params.cast::<f32>(),
                &Settings::default(),
                &rows,
                Backend32::Fast,
            )?;
            for (m, r) in sent.iter().zip(&replies) {
                msgs.push(*m);
                msgs.push(match r.answer {
                    Answer::Forces(f) => Msg::Forces(f),
                    Answer::Ack(code) => Msg::Ack(Ack {
                        of: MsgType::Measurement as u8,
                        seq: 0,
                        code,
                    }),
                });
                if let Some(e) = r.estimate {
                    msgs.push(Msg::Estimate(e));
                }
            }
            // The wheels' calibrations as the device reports them, and as a host hands them
            // back to start a device warm.
            if !batch {
                msgs.extend(cals.iter().map(|c| Msg::Calibration(*c)));
                msgs.extend(cals.iter().map(|c| Msg::SetCalibration(*c)));
            }
            let mut s = String::new();
            let mut seq = [0u8; id::ALL.len()];
            let mut rx: [Reassembler<MSG_BUF>; id::ALL.len()] = Default::default();
            for m in &msgs {
                let cid = id::of(m.msg_type());
                let k = id::ALL.iter().position(|x| x.0 == cid).unwrap_or(0);
                let sender = match (&mut signer, &mut device) {
                    (_, Some(d)) if is_answer(cid) => Sender::Device(d),
                    (Some(s), d) => Sender::Owner(s, d.is_some()),
                    _ => Sender::Plain,
                };
                let line = frames_json(m, cid, seq[k], mtu, &mut rx[k], sender)?;
                seq[k] = seq[k].wrapping_add(1);
                writeln!(s, "{line}").map_err(|e| e.to_string())?;
            }
            emit(&s, out)
        }
        ProtoCmd::Load {
            markdown,
            auth_mac_len,
        } => emit(
            &crate::busload::table_with(markdown, auth_mac_len.and_then(MacLen::new)),
            None,
        ),
    }
}

/// The log's rows grouped by sample time (consecutive rows with one `t_us`, distinct wheels)
/// into `CompactBatch`es, each followed by the `CompactResults` the device's pipeline answers
/// (run on the host on the values the batch carries, as the firmware's `process_batch`).
fn batches(
    p: &gough::mf::Params<f32>,
    rows: &[gough::proto::Measurement],
    msgs: &mut Vec<Msg>,
) -> Result<(), String> {
    let mut groups: Vec<Vec<gough::proto::Measurement>> = Vec::new();
    for m in rows {
        match groups.last_mut() {
            Some(g) if g[0].t_us == m.t_us && g.iter().all(|x| x.wheel != m.wheel) => g.push(*m),
            _ => groups.push(vec![*m]),
        }
    }
    let mut carried = Vec::new();
    let mut sent = Vec::new();
    for (i, g) in groups.iter().enumerate() {
        let b = CompactBatch::new(g[0].t_us, g).ok_or_else(|| {
            format!(
                "batch {}: a value out of the compact measurement's range",
                i + 1
            )
        })?;
        let ms = b.measurements();
        carried.extend(ms.iter().flatten().copied());
        sent.push(b);
    }
    // The pipeline runs per wheel in time order, as the device does wheel by wheel.
    let replies = replay::host_f32(p, &Settings::default(), &carried, Backend32::Fast)?;
    let mut r = replies.iter();
    for b in sent {
        let mut res = CompactResults {
            t_us: b.t_us,
            ..CompactResults::default()
        };
        for (m, out) in b.measurements().iter().zip(res.wheels.iter_mut()) {
            if m.is_some() {
                let reply = r.next().ok_or("fewer replies than measurements")?;
                let f = match reply.answer {
                    Answer::Forces(f) => Some(f),
                    Answer::Ack(_) => None,
                };
                *out = CompactWheelResult::or_na(f.as_ref(), reply.estimate.as_ref());
            }
        }
        msgs.push(Msg::CompactBatch(b));
        msgs.push(Msg::CompactResults(res));
    }
    Ok(())
}

fn hex(b: &[u8]) -> String {
    b.iter().fold(String::new(), |mut s, x| {
        let _ = write!(s, "{x:02x}");
        s
    })
}

/// Whether identifier `cid` carries the device's answers.
fn is_answer(cid: u16) -> bool {
    matches!(cid, id::RESULT | id::STATUS | id::BATCH_RESULT)
}

/// Who encodes a message: the owner's signer (every message when the flag is set, else the
/// state-changing ones), the device (its answers, secured under `Policy::All`), or nobody.
enum Sender<'a> {
    Owner(&'a mut Signer, bool),
    Device(&'a mut Verifier),
    Plain,
}

/// One message as a JSON line: its frames from the core's segmenter, and the message the
/// core's reassembler makes of them.
fn frames_json(
    m: &Msg,
    cid: u16,
    seq: u8,
    mtu: Mtu,
    rx: &mut Reassembler<MSG_BUF>,
    sender: Sender<'_>,
) -> Result<String, String> {
    let mut seg = match sender {
        Sender::Owner(s, all) if all || auth::is_state_changing(m) => {
            Segmenter::sealed(m, seq, mtu, s)
        }
        Sender::Device(d) => Segmenter::device(m, seq, mtu, d),
        _ => Segmenter::new(m, seq, mtu),
    }
    .map_err(|e| e.to_string())?;
    let encoded = hex(seg.encoded());
    let mut buf = [0u8; 64];
    let mut frames = Vec::new();
    let mut decoded = None;
    let mut secured = None;
    while let Some(f) = seg.next_frame(&mut buf) {
        frames.push(serde_json::Value::String(hex(f)));
        match rx.feed(f, 0) {
            Feed::Done(d) => {
                decoded = Some(d);
                if let Ok((_, Some(t))) = Msg::decode_secured(rx.last()) {
                    secured = Some(serde_json::json!({"counter": t.counter, "mac": hex(t.mac)}));
                }
            }
            Feed::Pending => {}
            Feed::Dropped(e) => return Err(format!("the host's reassembler dropped a frame: {e}")),
        }
    }
    let d = decoded.ok_or("the host's reassembler delivered no message")?;
    // Fixed-width integers serialise as byte arrays through serde: give them as numbers.
    let (kind, body, t_us, flags) = match d {
        Msg::Measurement(x) => ("Measurement", serde_json::to_value(x), Some(x.t_us), None),
        Msg::Forces(x) => (
            "Forces",
            serde_json::to_value(x),
            Some(x.t_us),
            Some(x.flags),
        ),
        Msg::Estimate(x) => ("Estimate", serde_json::to_value(x), Some(x.t_us), None),
        Msg::Ack(x) => ("Ack", serde_json::to_value(x), None, None),
        Msg::Calibration(x) | Msg::SetCalibration(x) => (
            d.msg_type().name(),
            Ok(serde_json::json!({
                "wheel": serde_json::to_value(x.wheel).map_err(|e| e.to_string())?,
                "value": x.value, "sigma": x.sigma, "batches": x.batches,
            })),
            None,
            None,
        ),
        Msg::CompactMeasurement(x) => (
            "CompactMeasurement",
            Ok(serde_json::json!({
                "wheel": serde_json::to_value(x.wheel).map_err(|e| e.to_string())?,
                "fz": x.fields.fz, "fy": x.fields.fy, "mz": x.fields.mz, "fx": x.fields.fx,
                "vx": x.fields.vx, "omega": x.fields.omega, "alpha": x.fields.alpha,
                "kappa": x.fields.kappa, "gamma": x.fields.gamma,
            })),
            Some(x.t_us),
            None,
        ),
        Msg::CompactBatch(x) => (
            "CompactBatch",
            Ok(serde_json::json!({
                "present": x.present,
                "wheels": x.wheels.iter().map(|w| serde_json::json!({
                    "fz": w.fz, "fy": w.fy, "mz": w.mz, "fx": w.fx, "vx": w.vx,
                    "omega": w.omega, "alpha": w.alpha, "kappa": w.kappa, "gamma": w.gamma,
                })).collect::<Vec<_>>(),
            })),
            Some(x.t_us),
            None,
        ),
        Msg::CompactResults(x) => (
            "CompactResults",
            Ok(serde_json::json!({
                "wheels": x.wheels.iter().map(|w| serde_json::json!({
                    "fx": w.fx, "fy": w.fy, "mz": w.mz, "mu": w.mu, "sigma": w.sigma,
                    "mu_min": w.mu_min, "status": w.status,
                })).collect::<Vec<_>>(),
            })),
            Some(x.t_us),
            None,
        ),
        other => return Err(format!("unexpected message {other:?}")),
    };
    let mut body = body.map_err(|e| e.to_string())?;
    if let Some(o) = body.as_object_mut() {
        if let Some(t) = t_us {
            o.insert("t_us".into(), t.into());
        }
        if let Some(f) = flags {
            o.insert("flags".into(), f.into());
        }
    }
    let kind = match secured {
        Some(_) => format!("{kind}Secured"),
        None => kind.to_string(),
    };
    let v = serde_json::json!({
        "id": cid,
        "type": kind,
        "secured": secured,
        "frames": frames,
        "encoded": encoded,
        "msg": body,
    });
    Ok(v.to_string())
}
