//! The bus description as a DBC file (`gough proto dbc`), generated from the tables of this
//! module so it cannot drift from the code.
//!
//! What a DBC can show of this protocol: per identifier, the frame header (first/last flags,
//! frame index, message sequence number) and, in first frames (multiplexed on the frame index
//! 0), the message length, the protocol version and the message type with its name. Message
//! bodies are postcard-encoded and segmented across frames, so their fields are not DBC
//! signals: decode them with `gough` or a client of this protocol.

use super::{id, MsgType, PROTO_VERSION};
use core::fmt::{self, Write};

/// Writes the DBC text.
pub fn write<W: Write>(w: &mut W) -> fmt::Result {
    writeln!(w, "VERSION \"gough-proto-{PROTO_VERSION}\"")?;
    writeln!(w)?;
    writeln!(w, "NS_ :")?;
    writeln!(w)?;
    writeln!(w, "BS_:")?;
    writeln!(w)?;
    writeln!(w, "BU_: HOST GOUGH")?;
    for (cid, name, dir) in id::ALL {
        let (tx, rx) = if dir == "host to device" {
            ("HOST", "GOUGH")
        } else {
            ("GOUGH", "HOST")
        };
        writeln!(w)?;
        writeln!(w, "BO_ {cid} {name}: 8 {tx}")?;
        writeln!(w, " SG_ frame_index M : 0|6@1+ (1,0) [0|63] \"\" {rx}")?;
        writeln!(w, " SG_ last_frame : 6|1@1+ (1,0) [0|1] \"\" {rx}")?;
        writeln!(w, " SG_ first_frame : 7|1@1+ (1,0) [0|1] \"\" {rx}")?;
        writeln!(w, " SG_ msg_seq : 8|8@1+ (1,0) [0|255] \"\" {rx}")?;
        writeln!(w, " SG_ msg_len m0 : 16|8@1+ (1,0) [6|255] \"byte\" {rx}")?;
        writeln!(w, " SG_ proto_version m0 : 24|8@1+ (1,0) [0|255] \"\" {rx}")?;
        writeln!(w, " SG_ msg_type m0 : 32|8@1+ (1,0) [0|255] \"\" {rx}")?;
    }
    writeln!(w)?;
    for (cid, _, dir) in id::ALL {
        write!(
            w,
            "CM_ BO_ {cid} \"gough protocol v{PROTO_VERSION}, {dir}: segmented messages (header, postcard body, CRC-32). Carries:"
        )?;
        for t in MsgType::ALL.iter().filter(|t| id::of(**t) == cid) {
            write!(w, " {}", t.name())?;
        }
        writeln!(w, "\";")?;
    }
    for (cid, _, _) in id::ALL {
        write!(w, "VAL_ {cid} msg_type")?;
        for t in MsgType::ALL.iter().filter(|t| id::of(**t) == cid) {
            write!(w, " {} \"{}\"", *t as u8, t.name())?;
        }
        writeln!(w, " ;")?;
    }
    Ok(())
}
