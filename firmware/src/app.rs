//! The application: protocol state, parameter upload, and at each tick every queued
//! measurement through its wheel's pipeline ([`gough::wheel`]: transient filter, Magic Formula,
//! friction estimator). Board independent: a board hands in its CAN driver (any
//! `embedded_can::nb::Can`) and a millisecond clock.
//!
//! ## The friction estimator
//! Each wheel runs the exact-model bank ([`gough::mu::bank::Bank`] in `f32`, through
//! [`gough::wheel::Car`]): the App starts the four wheels' estimators whenever a parameter set
//! is loaded (bundled or uploaded) and whenever `Settings` are applied (their `fallback_mu` is
//! the prior); the estimators forget what they learnt then. With the settings' `wheelbase`
//! (the car's, sent by the car or set by the board, [`App::apply_settings`]) each rear wheel's
//! estimator is told what the front wheel on its side read when it gets there
//! (`gough::mu::preview`). Starting one costs one Magic Formula
//! evaluation (the tyre's μy0), so the `ParamCommit` is acknowledged at once and estimates
//! follow from the next measurement on. The bank keeps no reference to the parameters: the App
//! owns them beside the wheels and hands them to each update. Its work per sample is bounded
//! (the `bench` output gives mean and worst instructions per wheel per sample); its state,
//! about 1.5 KB per wheel, lives in the App. A tyre the estimator cannot use (no friction at
//! FNOMIN) gets forces and no `Estimate`.
//!
//! ## Who may reconfigure it
//! Every state-changing message (upload, settings, calibration, reset, stop) must be secured
//! with the device key ([`gough::proto::auth`]): [`App::poll`] hands each complete message to
//! the [`Verifier`] first; a refused one is answered with its `Ack` code (`NoKey`,
//! `MacMissing`, `BadMac`, `StaleFreshness`), counted in `Status::auth`, and nothing it carried
//! takes effect (an upload in progress goes on). The board provisions the key and this boot's
//! epoch ([`App::provision`]); without them (`App::new`) the device refuses every
//! state-changing message.
//!
//! Provisioned with [`gough::proto::Policy::All`] (`--secure-all`), every message must be
//! secured — measurements, compact measurements and batches, status requests too — and the
//! device secures everything it sends with its own transmit counter. A refused message on a
//! measurement identifier (0x300, 0x302, 0x303) is counted in `Status::auth` and **not**
//! answered: at 4 wheels × 1 kHz an `Ack` per refused measurement would let any node make the
//! device flood the bus (each refused frame answered by a multi-frame secured `Ack`); a refused
//! message on the configuration identifier is still answered with its code (the owner's tool
//! needs it, and it comes at the sender's rate).
//!
//! ## The calibration
//! Each running estimator's calibration of the tyre (`gough::mu::calibration`) is reported as a
//! `Calibration` message once a second per wheel: one wheel every [`CAL_PERIOD_MS`] / 4, in
//! turn, at the end of a tick (after its forces and estimates). A `SetCalibration` hands a
//! wheel's estimator a calibration stored earlier (a warm start), acknowledged `Ok`,
//! `BadCalibration` (refused, its calibration stays) or `NoParams` (no estimator runs on that
//! wheel). A restart of the estimators (parameters, settings) forgets it: send it after them.

use gough::mf::Params;
use gough::proto::{
    self, crc32, id, link, Ack, AckCode, CalibrationState, Command, CompactBatch, CompactResults,
    CompactWheelResult, Estimate, Feed, Forces, Measurement, Msg, MsgType, Mtu, ParamSource,
    Reassembler, Segmenter, Settings, Status, Verifier, Wheel, MAX_TIR_LEN, MSG_BUF,
};
use gough::wheel::{self, Car};

/// The math backend of the device's pipeline: `gough::math::Fast` (feature `fast`, on by
/// default: as accurate as f32 libm and cheaper on the M4F, the `bench` output gives both
/// backends' instruction counts), else `gough::math::Libm`.
#[cfg(feature = "fast")]
pub type Math = gough::math::Fast;
/// The math backend of the device's pipeline (`fast` feature off: the libm reference).
#[cfg(not(feature = "fast"))]
pub type Math = gough::math::Libm;

/// Name of [`Math`], as the host's `gough replay --backend` spells it.
pub const MATH_NAME: &str = if cfg!(feature = "fast") {
    "fast"
} else {
    "libm"
};

/// Attempts per frame while the driver's transmit queue is full.
const TX_ATTEMPTS: u32 = 100_000;
/// Frames handled per [`App::poll`] call, so one call stays short.
const RX_BUDGET: usize = 64;
/// Measurements (single-wheel or four-wheel batches) waiting for the next tick.
pub const QUEUE: usize = 16;
/// Each wheel's calibration is reported once per this period \[ms\] (the wheels in turn).
pub const CAL_PERIOD_MS: u32 = 1000;

/// A queued piece of work: one wheel's measurement, or a four-wheel batch answered by one
/// `CompactResults`; each with the sequence number of its frames.
#[derive(Debug, Clone, Copy)]
enum Job {
    Single(Measurement, u8),
    Batch(CompactBatch),
}

/// What the board must do after [`App::poll`].
#[derive(Debug, Clone, Copy, PartialEq, Eq, defmt::Format)]
pub enum Event {
    /// `Command::Reset` was received (and acknowledged): reset the MCU.
    Reset,
    /// `Command::Stop` was received (QEMU board): the final `Status` is sent; exit.
    Stop,
}

#[derive(Debug, Clone, Copy)]
struct Upload {
    len: usize,
    got: usize,
    hash: u32,
}

/// The whole device state. ~41 KiB (the upload buffer is 32 KiB, the four wheels' estimators
/// ~6 KiB): keep it in a `static`.
pub struct App {
    params: Option<Params<f32>>,
    car: Car<f32>,
    source: ParamSource,
    hash: u32,
    upload: Option<Upload>,
    text: [u8; MAX_TIR_LEN],
    rx_meas: Reassembler<MSG_BUF>,
    rx_cfg: Reassembler<MSG_BUF>,
    rx_compact: Reassembler<MSG_BUF>,
    rx_batch: Reassembler<MSG_BUF>,
    queue: heapless::Deque<Job, QUEUE>,
    settings: Settings,
    eval_errors: u32,
    tx_messages: u32,
    tx_errors: u32,
    tx_seq: [u8; 3],
    /// Transport errors the board counted (SLCAN lines, overruns); reported in `Status`.
    pub link_errors: u32,
    /// Whether `Command::Stop` is honoured (QEMU) or answered `NotSupported`.
    pub can_stop: bool,
    /// Measures the deepest stack use \[bytes\] when a `Status` is built (the board's
    /// stack painting); `None`: reported as 0.
    pub stack_probe: Option<fn() -> u32>,
    now_ms: u32,
    auth: Verifier,
    /// Stores the epoch in the board's non-volatile memory when the verifier moves to the next
    /// one (after counter `u32::MAX`); `false`: not stored, and the device drops its key.
    pub epoch_store: Option<fn(u32) -> bool>,
    /// The wheel whose calibration is reported next, and when the last report went out \[ms\].
    cal_next: usize,
    cal_sent_ms: u32,
}

impl Default for App {
    fn default() -> Self {
        Self::new()
    }
}

impl App {
    /// Empty state: no parameters, default settings (`Settings::default()`).
    pub const fn new() -> Self {
        App {
            params: None,
            car: Car::new(),
            source: ParamSource::None,
            hash: 0,
            upload: None,
            text: [0; MAX_TIR_LEN],
            rx_meas: Reassembler::new(),
            rx_cfg: Reassembler::new(),
            rx_compact: Reassembler::new(),
            rx_batch: Reassembler::new(),
            queue: heapless::Deque::new(),
            settings: Settings {
                limits: true,
                fallback_mu: 0.3,
                wheelbase: 0.0,
            },
            eval_errors: 0,
            tx_messages: 0,
            tx_errors: 0,
            tx_seq: [0; 3],
            link_errors: 0,
            can_stop: false,
            stack_probe: None,
            now_ms: 0,
            auth: Verifier::without_key(),
            epoch_store: None,
            cal_next: 0,
            cal_sent_ms: 0,
        }
    }

    /// Provisions the key check: a [`Verifier`] with the device key, its MAC length and this
    /// boot's epoch (the board's non-volatile boot counter, raised at each boot).
    pub fn provision(&mut self, v: Verifier) {
        self.auth = v;
    }

    /// Loads a `.tir` text as the parameter set; on success the previous one is replaced.
    /// Returns the 1-based line of the first error otherwise.
    pub fn load_tir(&mut self, text: &str, source: ParamSource) -> Result<(), u32> {
        let t = gough::tir::parse(text).map_err(|e| e.line)?;
        self.set_params(t.params.cast::<f32>(), crc32(text.as_bytes()), source);
        defmt::info!(
            "parameters loaded: {=u32:x} ({} bytes, {} warnings)",
            self.hash,
            text.len(),
            t.warnings.len()
        );
        Ok(())
    }

    /// The parameter set in use.
    pub fn params(&self) -> Option<&Params<f32>> {
        self.params.as_ref()
    }

    /// Swaps in a parameter set: the filters restart, the estimators start on it.
    fn set_params(&mut self, p: Params<f32>, hash: u32, source: ParamSource) {
        self.params = Some(p);
        self.hash = hash;
        self.source = source;
        self.car.reset_filters();
        self.start_estimators();
    }

    /// (Re)starts the four wheels' estimators on the parameters in use, with the prior of the
    /// settings and the preview over their wheelbase, if any; without parameters (or for a tyre
    /// without friction) none runs. The settings in use were checked when applied.
    fn start_estimators(&mut self) {
        let Some(p) = self.params.as_ref() else {
            return;
        };
        // (The settings in use passed `Settings::wheelbase` when they were applied.)
        let preview = self.settings.preview().ok().flatten();
        let cfg = self.settings.estimator_config();
        if let Err(e) = self.car.start_estimators::<Math>(p, cfg, preview) {
            defmt::warn!("no estimator: {}", e);
        }
    }

    /// Applies settings (as a `Settings` message does): the estimators restart with the new
    /// prior and the preview over the new wheelbase (they forget what they learnt). Settings
    /// out of range ([`Settings::wheelbase`]) are refused with [`AckCode::BadSettings`] and the
    /// ones in use stay.
    pub fn apply_settings(&mut self, s: Settings) -> Result<(), AckCode> {
        s.wheelbase()?;
        self.settings = s;
        self.start_estimators();
        Ok(())
    }

    /// Wheel `i`'s estimator (0..=3), if it runs: its state, μy0 of the tyre
    /// (`Bank::mu0`), its count of refused samples (`Bank::bad_samples`).
    pub fn estimator(&self, i: usize) -> Option<&gough::mu::Bank<f32>> {
        proto::Wheel::from_index(i).and_then(|w| self.car.corner(w).estimator())
    }

    /// The status report.
    pub fn status(&self) -> Status {
        let mut rx = *self.rx_meas.counters();
        rx.add(self.rx_cfg.counters());
        rx.add(self.rx_compact.counters());
        rx.add(self.rx_batch.counters());
        Status {
            firmware: crate::VERSION,
            proto: proto::PROTO_VERSION,
            source: self.source,
            param_hash: self.hash,
            uptime_ms: self.now_ms,
            rx,
            link_errors: self.link_errors,
            eval_errors: self.eval_errors,
            tx_messages: self.tx_messages,
            stack_peak: self.stack_probe.map_or(0, |f| f()),
            auth: *self.auth.status(),
        }
    }

    fn send<C: embedded_can::nb::Can>(&mut self, can: &mut C, msg: &Msg) {
        let cid = id::of(msg.msg_type());
        let k = match cid {
            id::STATUS => 1,
            id::BATCH_RESULT => 2,
            _ => 0,
        };
        let seq = self.tx_seq.get(k).copied().unwrap_or(0);
        if let Some(s) = self.tx_seq.get_mut(k) {
            *s = seq.wrapping_add(1);
        }
        // Secured when the policy says so (the device's transmit counter, its epoch).
        let epoch = self.auth.epoch();
        let sent = Segmenter::device(msg, seq, Mtu::Classic, &mut self.auth)
            .map_err(link::SendError::Encode)
            .and_then(|seg| link::send_segments_nb(can, cid, seg, TX_ATTEMPTS));
        self.store_epoch_if_moved(epoch);
        match sent {
            Ok(()) => self.tx_messages = self.tx_messages.wrapping_add(1),
            Err(_) => self.tx_errors = self.tx_errors.wrapping_add(1),
        }
    }

    /// After the verifier moved to the next epoch (a counter reached `u32::MAX`, received or
    /// sent): stores it, or drops the key when it cannot.
    fn store_epoch_if_moved(&mut self, epoch: u32) {
        if self.auth.epoch() != epoch && !self.epoch_store.is_some_and(|f| f(self.auth.epoch())) {
            defmt::warn!("epoch not stored: the key is dropped");
            self.auth = Verifier::without_key();
        }
    }

    fn ack<C: embedded_can::nb::Can>(&mut self, can: &mut C, of: MsgType, seq: u8, code: AckCode) {
        self.send(
            can,
            &Msg::Ack(Ack {
                of: of as u8,
                seq,
                code,
            }),
        );
    }

    /// Receives what the driver has (at most a budget of frames), handles configuration and
    /// commands at once and queues measurements for [`App::tick`].
    pub fn poll<C: embedded_can::nb::Can>(&mut self, can: &mut C, now_ms: u32) -> Option<Event> {
        self.now_ms = now_ms;
        let _ = self.rx_meas.poll(now_ms);
        let _ = self.rx_cfg.poll(now_ms);
        let _ = self.rx_compact.poll(now_ms);
        let _ = self.rx_batch.poll(now_ms);
        for _ in 0..RX_BUDGET {
            let frame = match can.receive() {
                Ok(f) => f,
                Err(nb::Error::WouldBlock) => return None,
                Err(nb::Error::Other(_)) => {
                    self.link_errors = self.link_errors.wrapping_add(1);
                    continue;
                }
            };
            use embedded_can::Frame as _;
            let data = frame.data();
            let seq = data.get(1).copied().unwrap_or(0);
            let cid = link::standard_id(&frame);
            let rx = match cid {
                Some(id::MEASUREMENT) => &mut self.rx_meas,
                Some(id::CONFIG) => &mut self.rx_cfg,
                Some(id::COMPACT) => &mut self.rx_compact,
                Some(id::BATCH) => &mut self.rx_batch,
                _ => continue, // other traffic on the bus
            };
            match rx.feed(data, now_ms) {
                Feed::Pending => {}
                Feed::Dropped(e) => defmt::debug!("dropped: {}", e),
                Feed::Done(msg) => {
                    let epoch = self.auth.epoch();
                    let checked = self.auth.check(cid.unwrap_or(0), &msg, rx.last());
                    self.store_epoch_if_moved(epoch);
                    if let Err(r) = checked {
                        defmt::warn!("refused {}: {}", r.of, r.code);
                        // Counted; answered on the configuration identifier only (module doc).
                        if cid == Some(id::CONFIG) {
                            self.ack(can, r.of, seq, r.code);
                        }
                        continue;
                    }
                    if let Some(ev) = self.handle(can, msg, seq) {
                        return Some(ev);
                    }
                }
            }
        }
        None
    }

    fn handle<C: embedded_can::nb::Can>(
        &mut self,
        can: &mut C,
        msg: Msg,
        seq: u8,
    ) -> Option<Event> {
        let msg = match msg {
            // The same pipeline, on the measurement it stands for.
            Msg::CompactMeasurement(c) => Msg::Measurement(c.measurement()),
            other => other,
        };
        match msg {
            Msg::Measurement(m) => {
                if self.queue.push_back(Job::Single(m, seq)).is_err() {
                    self.eval_errors = self.eval_errors.wrapping_add(1);
                    defmt::warn!("measurement queue full");
                }
            }
            Msg::CompactBatch(b) => {
                if self.queue.push_back(Job::Batch(b)).is_err() {
                    self.eval_errors = self.eval_errors.wrapping_add(1);
                    defmt::warn!("measurement queue full");
                }
            }
            Msg::ParamBegin(b) => {
                let len = usize::try_from(b.len).unwrap_or(usize::MAX);
                let code = if len == 0 || len > MAX_TIR_LEN {
                    self.upload = None;
                    AckCode::BadLength
                } else {
                    self.upload = Some(Upload {
                        len,
                        got: 0,
                        hash: b.hash,
                    });
                    AckCode::Ok
                };
                self.ack(can, MsgType::ParamBegin, seq, code);
            }
            Msg::ParamChunk(c) => {
                let code = match self.upload.as_mut() {
                    None => Some(AckCode::NotInUpload),
                    Some(u) if usize::try_from(c.offset).ok() != Some(u.got) => {
                        Some(AckCode::BadOffset)
                    }
                    Some(u) => {
                        let d = c.data.as_slice();
                        let end = u.got.saturating_add(d.len());
                        match self.text.get_mut(u.got..end).filter(|_| end <= u.len) {
                            Some(dst) => {
                                dst.copy_from_slice(d);
                                u.got = end;
                                None
                            }
                            None => Some(AckCode::BadLength),
                        }
                    }
                };
                if let Some(code) = code {
                    self.upload = None;
                    self.ack(can, MsgType::ParamChunk, seq, code);
                }
            }
            Msg::ParamCommit(c) => {
                let code = match self.upload.take() {
                    None => AckCode::NotInUpload,
                    Some(u) if u.got != u.len => AckCode::BadLength,
                    Some(u) => {
                        let text = self.text.get(..u.len).unwrap_or(&[]);
                        if crc32(text) != u.hash || c.hash != u.hash {
                            AckCode::BadHash
                        } else {
                            match core::str::from_utf8(text) {
                                Err(_) => AckCode::TirError { line: 0 },
                                Ok(s) => {
                                    // Copy out of `self.text` borrow: parse needs &mut self after.
                                    match gough::tir::parse(s) {
                                        Ok(t) => {
                                            let p = t.params.cast::<f32>();
                                            self.set_params(p, u.hash, ParamSource::Uploaded);
                                            defmt::info!("uploaded parameters {=u32:x}", u.hash);
                                            AckCode::Ok
                                        }
                                        Err(e) => AckCode::TirError { line: e.line },
                                    }
                                }
                            }
                        }
                    }
                };
                // The estimators are started on the new tyre already (`set_params`).
                self.ack(can, MsgType::ParamCommit, seq, code);
            }
            Msg::SetCalibration(c) => {
                let code = self.set_calibration(&c);
                self.ack(can, MsgType::SetCalibration, seq, code);
            }
            Msg::Settings(s) => {
                let code = match self.apply_settings(s) {
                    Ok(()) => AckCode::Ok,
                    Err(c) => c,
                };
                self.ack(can, MsgType::Settings, seq, code);
            }
            Msg::Command(Command::StatusRequest) => {
                let s = self.status();
                self.send(can, &Msg::Status(s));
            }
            Msg::Command(Command::Reset) => {
                self.ack(can, MsgType::Command, seq, AckCode::Ok);
                return Some(Event::Reset);
            }
            Msg::Command(Command::Stop) => {
                if self.can_stop {
                    let s = self.status();
                    self.send(can, &Msg::Status(s));
                    return Some(Event::Stop);
                }
                self.ack(can, MsgType::Command, seq, AckCode::NotSupported);
            }
            // Device → host messages on our receive identifiers: not for us.
            Msg::Forces(_)
            | Msg::Estimate(_)
            | Msg::Status(_)
            | Msg::Ack(_)
            | Msg::Calibration(_)
            | Msg::CompactResults(_) => {}
            Msg::CompactMeasurement(_) => {} // turned into a Measurement above
        }
        None
    }

    /// One fixed-rate step: every queued measurement through its wheel's pipeline → `Forces`
    /// (or an `Ack` saying why not), then `Estimate` when the estimator runs; every queued
    /// batch → one `CompactResults` ([`App::process_batch`]).
    pub fn tick<C: embedded_can::nb::Can>(&mut self, can: &mut C, now_ms: u32) {
        self.now_ms = now_ms;
        while let Some(job) = self.queue.pop_front() {
            let (m, seq) = match job {
                Job::Single(m, seq) => (m, seq),
                Job::Batch(b) => {
                    let r = self.process_batch(&b);
                    self.send(can, &Msg::CompactResults(r));
                    continue;
                }
            };
            let (forces, estimate) = self.process(&m);
            match forces {
                Ok(f) => self.send(can, &Msg::Forces(f)),
                Err(code) => {
                    self.eval_errors = self.eval_errors.wrapping_add(1);
                    self.ack(can, MsgType::Measurement, seq, code);
                }
            }
            if let Some(e) = estimate {
                self.send(can, &Msg::Estimate(e));
            }
        }
        if let Some(c) = self.calibration_due(now_ms) {
            self.send(can, &Msg::Calibration(c));
        }
    }

    /// Wheel `c.wheel`'s estimator starts from calibration `c` (as a `SetCalibration` does):
    /// `Ok`, `BadCalibration` when it refuses it (nothing changed), `NoParams` when no
    /// estimator runs on that wheel.
    pub fn set_calibration(&mut self, c: &CalibrationState) -> AckCode {
        match self.car.estimator_mut(c.wheel) {
            None => AckCode::NoParams,
            Some(b) => match b.import_calibration::<Math>(&c.exported()) {
                Ok(()) => AckCode::Ok,
                Err(_) => AckCode::BadCalibration,
            },
        }
    }

    /// The calibration report due at `now_ms`, if any: every [`CAL_PERIOD_MS`] / 4 the next
    /// wheel in turn whose estimator runs (so each wheel once per period; none without
    /// estimators).
    pub fn calibration_due(&mut self, now_ms: u32) -> Option<CalibrationState> {
        if now_ms.wrapping_sub(self.cal_sent_ms) < CAL_PERIOD_MS / 4 {
            return None;
        }
        self.cal_sent_ms = now_ms;
        for _ in 0..Wheel::ALL.len() {
            let w = Wheel::from_index(self.cal_next)?;
            self.cal_next = (self.cal_next + 1) % Wheel::ALL.len();
            if let Some(b) = self.car.corner(w).estimator() {
                return Some(CalibrationState::new(w, &b.calibration().export::<Math>()));
            }
        }
        None
    }

    /// One measurement through its wheel's pipeline ([`gough::wheel`]): the forces (or why
    /// none) and the estimate (when the estimator runs). The host's replay check runs the same.
    pub fn process(&mut self, m: &Measurement) -> (Result<Forces, AckCode>, Option<Estimate>) {
        let Some(p) = self.params.as_ref() else {
            return (Err(AckCode::NoParams), None);
        };
        let x = wheel::Measurement::from(m);
        let forces = self
            .car
            .forces::<Math>(p, self.settings.limits, m.wheel, &x)
            .map(|o| Forces::new(m.wheel, m.t_us, &o))
            .map_err(AckCode::from);
        let estimate = self
            .car
            .estimate::<Math>(p, m.wheel, &x)
            .map(|e| Estimate::new(m.wheel, m.t_us, &e));
        if let Some(e) = estimate.filter(|e| e.change) {
            defmt::info!("wheel {}: change of surface, mu {}", m.wheel, e.mu);
        }
        (forces, estimate)
    }

    /// A four-wheel batch: each present wheel's measurement through its pipeline as
    /// [`App::process`] does, in wheel order, gathered into one `CompactResults`. A wheel
    /// without forces (no parameters, no slip, evaluation error; counted in `eval_errors`) or
    /// with a value the message cannot represent gets "not available" there
    /// (`CompactWheelResult::or_na`).
    pub fn process_batch(&mut self, b: &CompactBatch) -> CompactResults {
        let mut r = CompactResults {
            t_us: b.t_us,
            ..CompactResults::default()
        };
        for (m, out) in b.measurements().iter().zip(r.wheels.iter_mut()) {
            let Some(m) = m else { continue };
            let (forces, estimate) = self.process(m);
            if forces.is_err() {
                self.eval_errors = self.eval_errors.wrapping_add(1);
            }
            *out = CompactWheelResult::or_na(forces.ok().as_ref(), estimate.as_ref());
        }
        r
    }

    /// The steady-state forces of one sample, without the filter (the selftest's oracle point:
    /// the tyre as its file describes it, whichever wheel the sample names).
    pub fn evaluate(&self, m: &Measurement) -> Result<Forces, AckCode> {
        let p = self.params.as_ref().ok_or(AckCode::NoParams)?;
        wheel::steady::<f32, Math>(p, self.settings.limits, None, &m.into())
            .map(|o| Forces::new(m.wheel, m.t_us, &o))
            .map_err(AckCode::from)
    }
}
