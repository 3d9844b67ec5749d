//! `gough proto load`: the bus-load table's frame counts are the segmenter's, and its rows
//! follow from them (frames/s = frames per wheel-sample × rate × 4 wheels).
use gough::proto::{Msg, Mtu, Segmenter};
use gough_host::busload::{self, BUSES, RATES, WHEELS};
use gough_host_tests::gough_bin;
use std::process::Command;

/// Frames the core's segmenter writes for `m`, counted one by one.
fn count(m: &Msg, mtu: Mtu) -> usize {
    let mut s = Segmenter::new(m, 0, mtu).unwrap();
    let mut b = [0u8; 64];
    let mut n = 0;
    while s.next_frame(&mut b).is_some() {
        n += 1;
    }
    assert_eq!(n, s.frame_count());
    n
}

#[test]
fn frame_counts_are_the_segmenters() {
    // The figure: a measurement with every optional field takes 10 classic frames
    // (58 bytes: 5 in the first frame, 6 in each of 9 more); without them, 6 (30 bytes).
    assert_eq!(count(&busload::measurement(true), Mtu::Classic), 10);
    assert_eq!(count(&busload::measurement(false), Mtu::Classic), 6);
    // The compact measurement (29 bytes): 5 classic frames, one FD frame.
    assert!(matches!(busload::compact(), Msg::CompactMeasurement(_)));
    assert_eq!(count(&busload::compact(), Mtu::Classic), 5);
    assert_eq!(count(&busload::compact(), Mtu::Fd), 1);
    // Forces (25 bytes) 5 frames, Estimate (25 bytes since protocol v2: μ_min and the change
    // flag) 5; on FD one frame each.
    let r = busload::results();
    assert_eq!(count(&r[0], Mtu::Classic), 5);
    assert_eq!(count(&r[1], Mtu::Classic), 5);
    assert_eq!(count(&r[0], Mtu::Fd) + count(&r[1], Mtu::Fd), 2);
    // The four-wheel batch (83 bytes): two 48-byte FD frames, 14 classic; its results (58
    // bytes): one 64-byte FD frame, 10 classic.
    assert!(matches!(busload::batch(), Msg::CompactBatch(_)));
    assert!(matches!(busload::batch_results(), Msg::CompactResults(_)));
    assert_eq!(count(&busload::batch(), Mtu::Fd), 2);
    assert_eq!(count(&busload::batch(), Mtu::Classic), 14);
    assert_eq!(count(&busload::batch_results(), Mtu::Fd), 1);
    assert_eq!(count(&busload::batch_results(), Mtu::Classic), 10);
    for bus in &BUSES {
        for (_, msgs, _) in busload::traffics() {
            let n: usize = msgs.iter().map(|m| count(m, bus.mtu)).sum();
            assert_eq!(busload::per_sample(&msgs, bus).0, n);
        }
    }
}

#[test]
fn cli_table_rows_follow_from_the_frame_counts() {
    let out = Command::new(gough_bin())
        .args(["proto", "load", "--markdown"])
        .output()
        .unwrap();
    assert!(out.status.success());
    let text = String::from_utf8(out.stdout).unwrap();
    let tr = busload::traffics();
    let mut rows = 0;
    for bus in &BUSES {
        for rate in RATES {
            let head = format!("| {} | {rate} Hz |", bus.name);
            let line = text.lines().find(|l| l.starts_with(&head)).expect(&head);
            let cells: Vec<&str> = line[head.len()..].split('|').map(str::trim).collect();
            for (k, (_, msgs, per)) in tr.iter().enumerate() {
                let n: usize = msgs.iter().map(|m| count(m, bus.mtu)).sum();
                // Per wheel-sample (× 4 wheels) or per four-wheel batch (× 1).
                assert!(*per == WHEELS || *per == 1.0);
                let fps = n as f64 * rate * per;
                assert!(
                    cells[k].starts_with(&format!("{fps:.0} f/s")),
                    "{head} {}: {} != {fps}",
                    tr[k].0,
                    cells[k]
                );
                let load: f64 = cells[k]
                    .split(", ")
                    .nth(1)
                    .unwrap()
                    .split(' ')
                    .next()
                    .unwrap()
                    .parse()
                    .unwrap();
                let fits = !cells[k].contains('✗');
                assert_eq!(fits, load <= 60.0, "{line}");
            }
            rows += 1;
        }
    }
    assert_eq!(rows, 12);
    // Classic 1 Mbit/s, 1 kHz, all fields both ways: 4 × 1000 × (10 + 10) frames of 135 bits
    // or fewer: does not fit.
    assert!(text.contains("| classic 1 Mbit/s | 1000 Hz | 40000 f/s"));
    // Four wheels at 1 kHz both ways as batches: 3 frames per millisecond on CAN FD (two of
    // 48 bytes in, one of 64 out), fits 500 k / 5 M, not 500 k / 2 M.
    let last = |bus: &str| {
        let head = format!("| {bus} | 1000 Hz |");
        let line = text.lines().find(|l| l.starts_with(&head)).unwrap();
        line.trim_end_matches('|')
            .rsplit('|')
            .next()
            .unwrap()
            .trim()
            .to_string()
    };
    let fd5 = last("FD 500 k / 5 M");
    assert!(fd5.starts_with("3000 f/s") && !fd5.contains('✗'), "{fd5}");
    let fd2 = last("FD 500 k / 2 M");
    assert!(fd2.starts_with("3000 f/s") && fd2.contains('✗'), "{fd2}");
}
