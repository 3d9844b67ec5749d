//! The fuzz targets' seed corpora (`fuzz/corpus/msg_decode`, `fuzz/corpus/reassembler`) are real
//! messages of this protocol version, CRC included: a seed the decoder drops at its version byte
//! (after a `PROTO_VERSION` change) would leave the fuzzer to rediscover every body from scratch.
use gough::proto::{Feed, Msg, Reassembler, MSG_BUF, PROTO_VERSION};
use std::path::Path;

fn seeds(dir: &str) -> Vec<(String, Vec<u8>)> {
    let d = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../fuzz/corpus")
        .join(dir);
    let mut v: Vec<_> = std::fs::read_dir(&d)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|x| x == "bin"))
        .map(|p| (p.display().to_string(), std::fs::read(&p).unwrap()))
        .collect();
    v.sort();
    v
}

#[test]
fn msg_decode_seeds_are_messages_of_this_version() {
    let s = seeds("msg_decode");
    assert!(s.len() >= 4);
    let (mut estimate, mut batch, mut results, mut settings) = (false, false, false, false);
    for (name, b) in &s {
        assert_eq!(b.first(), Some(&PROTO_VERSION), "{name}");
        let m = Msg::decode(b).unwrap_or_else(|e| panic!("{name}: {e:?}"));
        estimate |= matches!(m, Msg::Estimate(e) if e.change);
        batch |= matches!(m, Msg::CompactBatch(b) if b.present != 0);
        results |= matches!(m, Msg::CompactResults(_));
        settings |= matches!(m, Msg::Settings(s) if s.wheelbase > 0.0);
    }
    assert!(estimate, "a seed with an Estimate and its change flag");
    assert!(settings, "a seed with Settings and a wheelbase");
    assert!(
        batch && results,
        "seeds with a four-wheel batch and its results"
    );
}

#[test]
fn reassembler_seeds_deliver_their_message() {
    let s = seeds("reassembler");
    assert!(s.len() >= 4);
    for (name, b) in &s {
        // The target's input: [len (bit 7: time step), frame bytes...] records.
        let mut r = Reassembler::<MSG_BUF>::new();
        let (mut rest, mut now, mut done) = (&b[..], 0u32, 0);
        while let Some((&head, tail)) = rest.split_first() {
            let n = usize::from(head & 0x7F).min(tail.len());
            now = now.wrapping_add(u32::from(head >> 7) * 60);
            let (frame, t) = tail.split_at(n);
            rest = t;
            if let Feed::Done(_) = r.feed(frame, now) {
                done += 1;
            }
        }
        assert_eq!(done, 1, "{name}: {:?}", r.counters());
    }
}
