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

/// Re-seals the seed corpora for this protocol version after a version change (run by hand:
/// `cargo test -p gough-host-tests --test fuzz_seeds -- --ignored`): the version byte, a
/// body that grew at its end (v5: `Status`'s `auth`, all zero), the CRC; the reassembler's
/// seeds reassembled, patched the same way and segmented again (their time steps dropped).
#[test]
#[ignore]
fn reseal_seeds_for_this_version() {
    use gough::proto::{crc32, Mtu, Segmenter};
    fn patch(msg: &[u8]) -> Vec<u8> {
        let mut data = msg[..msg.len() - 4].to_vec();
        if data[0] == PROTO_VERSION {
            return msg.to_vec();
        }
        assert_eq!(data[0], PROTO_VERSION - 1, "one version at a time");
        data[0] = PROTO_VERSION;
        if data[1] == gough::proto::MsgType::Status as u8 {
            // auth: mac_len u8, epoch and counter u32, five varint counters: all zero.
            data.extend_from_slice(&[0; 14]);
        }
        let c = crc32(&data).to_le_bytes();
        data.extend_from_slice(&c);
        Msg::decode(&data).unwrap_or_else(|e| panic!("{e:?}"));
        data
    }
    for (name, b) in seeds("msg_decode") {
        std::fs::write(&name, patch(&b)).unwrap();
    }
    for (name, b) in seeds("reassembler") {
        // Records [len | time bit, frame...]: the message's bytes from the frames (first:
        // [flags, seq, len, bytes...]; the others: [flags, seq, bytes...]).
        let (mut rest, mut bytes, mut total, mut seq, mut fd) = (&b[..], Vec::new(), 0, 0, false);
        while let Some((&head, tail)) = rest.split_first() {
            let n = usize::from(head & 0x7F).min(tail.len());
            let (f, t) = tail.split_at(n);
            rest = t;
            if f.len() < 3 {
                continue;
            }
            if f[0] & 0x80 != 0 {
                (bytes, total, seq, fd) = (f[3..].to_vec(), usize::from(f[2]), f[1], f.len() > 8);
            } else {
                bytes.extend_from_slice(&f[2..]);
            }
        }
        bytes.truncate(total);
        let m = Msg::decode(&patch(&bytes)).unwrap();
        let mtu = if fd { Mtu::Fd } else { Mtu::Classic };
        let mut s = Segmenter::new(&m, seq, mtu).unwrap();
        let (mut out, mut buf) = (Vec::new(), [0u8; 64]);
        while let Some(f) = s.next_frame(&mut buf) {
            out.push(u8::try_from(f.len()).unwrap());
            out.extend_from_slice(f);
        }
        std::fs::write(&name, out).unwrap();
    }
}
