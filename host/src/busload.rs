//! Bus load of the protocol: frames per second and the share of the bus they take, for four
//! wheels streaming [`Msg::Measurement`]s and the device answering each with [`Msg::Forces`]
//! and [`Msg::Estimate`], or the four wheels in one [`Msg::CompactBatch`] answered by one
//! [`Msg::CompactResults`] (`gough proto load`, the table in docs/protocol.md).
//!
//! Frame counts and lengths are the core's: each message is cut by [`Segmenter`], and every
//! frame it writes is timed. Frame time in bits, 11-bit identifiers, worst-case stuffing:
//! - classic CAN (ISO 11898-1; Davis, Burns, Bril, Lukkien 2007, eq. (1)): `47 + 8n` bits
//!   plus at most `⌊(34 + 8n − 1)/4⌋` stuff bits (135 bits for n = 8), all at the bit rate;
//! - CAN FD with bit-rate switching: at the nominal rate, SOF to BRS (17 bits) with at most 4
//!   stuff bits, and CRC delimiter, ACK, ACK delimiter, EOF and intermission (13 bits); at the
//!   data rate, ESI and DLC (5) and the data (8n) with at most `⌈(5 + 8n)/4⌉` stuff bits (a
//!   bound that also covers a stuff run carried over from the arbitration field), the stuff
//!   count (4), the CRC (17 bits for n ≤ 16, else 21) and its fixed stuff bits (6, else 7).
//!
//! Load = Σ frames/s × frame time; a configuration "fits" at ≤ 60 % (the margin left for the
//! other traffic of a vehicle bus and for retransmissions after errors).

use gough::proto::{
    CompactBatch, CompactMeasurement, CompactResults, CompactWheelResult, Estimate, Forces, Key,
    MacLen, Measurement, Msg, Mtu, Segmenter, Signer, Wheel,
};
use std::fmt::Write as _;

/// A CAN bus: its frame format and bit rates.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Bus {
    /// Name as printed.
    pub name: &'static str,
    /// Classic or FD frames.
    pub mtu: Mtu,
    /// Nominal (arbitration) bit rate \[bit/s\].
    pub nominal: f64,
    /// Data-phase bit rate \[bit/s\] (= nominal on classic CAN).
    pub data: f64,
}

/// The buses of the table.
pub const BUSES: [Bus; 4] = [
    Bus {
        name: "classic 500 kbit/s",
        mtu: Mtu::Classic,
        nominal: 500e3,
        data: 500e3,
    },
    Bus {
        name: "classic 1 Mbit/s",
        mtu: Mtu::Classic,
        nominal: 1e6,
        data: 1e6,
    },
    Bus {
        name: "FD 500 k / 2 M",
        mtu: Mtu::Fd,
        nominal: 500e3,
        data: 2e6,
    },
    Bus {
        name: "FD 500 k / 5 M",
        mtu: Mtu::Fd,
        nominal: 500e3,
        data: 5e6,
    },
];

/// Sample rates per wheel of the table \[Hz\].
pub const RATES: [f64; 3] = [100.0, 500.0, 1000.0];

/// Wheels streaming.
pub const WHEELS: f64 = 4.0;

/// Largest load that counts as fitting.
pub const FITS: f64 = 0.60;

/// Worst-case time on the bus of one data frame with `n` data bytes, 11-bit identifier \[s\].
pub fn frame_time(bus: &Bus, n: usize) -> f64 {
    let n = n as f64;
    match bus.mtu {
        Mtu::Classic => {
            let bits = 47.0 + 8.0 * n + ((34.0 + 8.0 * n - 1.0) / 4.0).floor();
            bits / bus.nominal
        }
        Mtu::Fd => {
            let nominal = 17.0 + 4.0 + 13.0;
            let (crc, fsb) = if n <= 16.0 { (17.0, 6.0) } else { (21.0, 7.0) };
            let data = 5.0 + 8.0 * n + ((5.0 + 8.0 * n) / 4.0).ceil() + 4.0 + crc + fsb;
            nominal / bus.nominal + data / bus.data
        }
    }
}

/// The data lengths of the frames that carry `m` on a bus of `mtu` (the segmenter's frames).
pub fn frame_lengths(m: &Msg, mtu: Mtu) -> Vec<usize> {
    frame_lengths_with(m, mtu, None)
}

/// As [`frame_lengths`], the message secured with MACs of `auth` bytes when given
/// (`proto::auth`: 4 counter bytes and the MAC more).
pub fn frame_lengths_with(m: &Msg, mtu: Mtu, auth: Option<MacLen>) -> Vec<usize> {
    let seg = match auth {
        Some(n) => Segmenter::sealed(m, 0, mtu, &mut Signer::new(Key::new([0; 16]), n, 1, 0)),
        None => Segmenter::new(m, 0, mtu),
    };
    let Ok(mut s) = seg else {
        return Vec::new();
    };
    let mut buf = [0u8; 64];
    let mut out = Vec::new();
    while let Some(f) = s.next_frame(&mut buf) {
        out.push(f.len());
    }
    out
}

/// A measurement with every optional field (`full`) or with none.
pub fn measurement(full: bool) -> Msg {
    let o = |v: f32| full.then_some(v);
    Msg::Measurement(Measurement {
        wheel: Wheel::RearRight,
        t_us: 1_000_000,
        fz: 4000.0,
        fy: -1500.0,
        mz: 40.0,
        fx: o(300.0),
        vx: o(16.7),
        omega: o(52.0),
        delta: o(0.02),
        alpha: o(0.03),
        kappa: o(0.01),
        gamma: o(0.0),
    })
}

/// What the device sends back per measurement: forces and an estimate.
pub fn results() -> [Msg; 2] {
    [
        Msg::Forces(Forces {
            wheel: Wheel::RearRight,
            t_us: 1_000_000,
            fx: 300.0,
            fy: -1500.0,
            mz: 40.0,
            flags: 0,
        }),
        Msg::Estimate(Estimate {
            wheel: Wheel::RearRight,
            t_us: 1_000_000,
            mu: 0.9,
            sigma: 0.05,
            state: gough::mu::State::Identifiable,
            mu_min: 0.75,
            change: false,
            mismatch: false,
        }),
    ]
}

/// Frames and bus time \[s\] per wheel-sample of a set of messages.
pub fn per_sample(msgs: &[Msg], bus: &Bus) -> (usize, f64) {
    per_sample_with(msgs, bus, None)
}

/// As [`per_sample`], every message secured with MACs of `auth` bytes when given.
pub fn per_sample_with(msgs: &[Msg], bus: &Bus, auth: Option<MacLen>) -> (usize, f64) {
    msgs.iter().fold((0, 0.0), |(n, t), m| {
        let l = frame_lengths_with(m, bus.mtu, auth);
        (
            n + l.len(),
            t + l.iter().map(|&b| frame_time(bus, b)).sum::<f64>(),
        )
    })
}

/// The measurement with every optional field as a [`CompactMeasurement`].
pub fn compact() -> Msg {
    match measurement(true) {
        Msg::Measurement(m) => CompactMeasurement::new(&m)
            .map(Msg::CompactMeasurement)
            .unwrap_or(Msg::Measurement(m)),
        other => other,
    }
}

/// The four wheels' measurements with every optional field as one [`CompactBatch`].
pub fn batch() -> Msg {
    let ms = Wheel::ALL.map(|w| match measurement(true) {
        Msg::Measurement(m) => Measurement { wheel: w, ..m },
        _ => Measurement::default(),
    });
    CompactBatch::new(1_000_000, &ms)
        .map(Msg::CompactBatch)
        .unwrap_or(Msg::Measurement(ms[0]))
}

/// The four wheels' [`results`] as one [`CompactResults`].
pub fn batch_results() -> Msg {
    let w = match results() {
        [Msg::Forces(f), Msg::Estimate(e)] => CompactWheelResult::or_na(Some(&f), Some(&e)),
        _ => CompactWheelResult::default(),
    };
    Msg::CompactResults(CompactResults {
        t_us: 1_000_000,
        wheels: [w; 4],
    })
}

/// Messages per sample instant of the four wheels: per wheel ([`WHEELS`]) or one for all four.
pub const PER_WHEEL: f64 = WHEELS;
/// One message (set) carries all four wheels.
pub const PER_BATCH: f64 = 1.0;

/// One traffic of the table: a name, the messages it sends per unit, and the units per sample
/// instant ([`PER_WHEEL`]: the messages are sent for each wheel; [`PER_BATCH`]: once for the
/// four wheels).
pub fn traffics() -> [(&'static str, Vec<Msg>, f64); 10] {
    let r = results();
    [
        (
            "measurement, all fields",
            vec![measurement(true)],
            PER_WHEEL,
        ),
        (
            "measurement, no optional fields",
            vec![measurement(false)],
            PER_WHEEL,
        ),
        ("compact measurement", vec![compact()], PER_WHEEL),
        ("results (Forces + Estimate)", r.to_vec(), PER_WHEEL),
        (
            "both ways, all fields",
            vec![measurement(true), r[0], r[1]],
            PER_WHEEL,
        ),
        (
            "both ways, no optional fields",
            vec![measurement(false), r[0], r[1]],
            PER_WHEEL,
        ),
        ("both ways, compact", vec![compact(), r[0], r[1]], PER_WHEEL),
        ("four-wheel batch in", vec![batch()], PER_BATCH),
        ("four-wheel results out", vec![batch_results()], PER_BATCH),
        (
            "both ways, four-wheel",
            vec![batch(), batch_results()],
            PER_BATCH,
        ),
    ]
}

/// The table: frames/s and load per bus, rate and traffic.
pub fn table(markdown: bool) -> String {
    table_with(markdown, None)
}

/// As [`table`], every message secured with MACs of `auth` bytes when given (the cost of
/// authenticating measurements and answers too).
pub fn table_with(markdown: bool, auth: Option<MacLen>) -> String {
    let tr = traffics();
    let mut s = String::new();
    let _ = write!(s, "| bus | rate/wheel |");
    for (name, ..) in &tr {
        let _ = write!(s, " {name} |");
    }
    let _ = writeln!(s);
    if markdown {
        let _ = writeln!(s, "|---|---:|{}", "---:|".repeat(tr.len()));
    }
    for bus in &BUSES {
        for rate in RATES {
            let _ = write!(s, "| {} | {rate} Hz |", bus.name);
            for (_, msgs, per) in &tr {
                let (n, t) = per_sample_with(msgs, bus, auth);
                let fps = n as f64 * rate * per;
                let load = t * rate * per;
                let mark = if load <= FITS { "" } else { " ✗" };
                let _ = write!(s, " {fps:.0} f/s, {:.0} %{mark} |", load * 100.0);
            }
            let _ = writeln!(s);
        }
    }
    let _ = writeln!(
        s,
        "\n{} wheels; frames per wheel-sample (per four-wheel sample for the batch columns) and bus time from the core's segmenter, worst-case bit stuffing, 11-bit identifiers; ✗: above {:.0} % load.",
        WHEELS,
        FITS * 100.0
    );
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn classic_frame_of_8_bytes_is_135_bits() {
        // Davis et al. (2007): 135 bit times for an 8-byte frame, 11-bit identifier.
        let b = &BUSES[1];
        assert!((frame_time(b, 8) * 1e6 - 135.0).abs() < 1e-9);
        assert!((frame_time(b, 0) * 1e6 - 55.0).abs() < 1e-9);
    }

    #[test]
    fn fd_frame_times() {
        let b = &BUSES[2];
        // 64 bytes: 34 nominal bits (68 µs) + 5 + 512 + 130 + 4 + 21 + 7 = 679 data bits.
        assert!((frame_time(b, 64) * 1e6 - (68.0 + 679.0 / 2.0)).abs() < 1e-9);
        // 8 bytes: 5 + 64 + 18 + 4 + 17 + 6 = 114 data bits.
        assert!((frame_time(b, 8) * 1e6 - (68.0 + 114.0 / 2.0)).abs() < 1e-9);
    }

    #[test]
    fn a_secured_message_is_4_plus_mac_bytes_longer() {
        let m = measurement(true);
        let len = |auth| {
            frame_lengths_with(&m, Mtu::Classic, auth)
                .iter()
                .sum::<usize>()
        };
        // 58 bytes: 10 classic frames (5 + 9 × 6 bytes); secured with 8-byte MACs 70 bytes: 12;
        // with 4-byte MACs 66 bytes: 12 too (5 + 10 × 6 = 65).
        assert_eq!(frame_lengths(&m, Mtu::Classic).len(), 10);
        assert_eq!(
            frame_lengths_with(&m, Mtu::Classic, MacLen::new(8)).len(),
            12
        );
        assert_eq!(
            frame_lengths_with(&m, Mtu::Classic, MacLen::new(4)).len(),
            12
        );
        assert_eq!(len(MacLen::new(8)), 12 * 8);
        // CAN FD (64-byte frames on the measurement identifier): 1 frame, 2 secured.
        assert_eq!(frame_lengths(&m, Mtu::Fd).len(), 1);
        assert_eq!(frame_lengths_with(&m, Mtu::Fd, MacLen::new(8)).len(), 2);
    }
}
