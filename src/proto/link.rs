//! Messages over any CAN driver that implements the `embedded-can` traits (a HAL's bxCAN or
//! FDCAN, the firmware's SLCAN-over-UART, the host's SLCAN-over-TCP).

use super::{Error, Msg, Mtu, Segmenter};
use embedded_can::{Frame as _, Id, StandardId};

/// Why a message was not sent.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum SendError<E> {
    /// The message did not encode (never happens with the crate's buffers).
    Encode(Error),
    /// The driver's frame type rejected an identifier or a length.
    Frame,
    /// The driver stayed busy for the allowed number of attempts.
    Busy,
    /// The driver failed.
    Can(E),
}

impl<E: core::fmt::Debug> core::fmt::Display for SendError<E> {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            SendError::Encode(e) => write!(f, "encode: {e}"),
            SendError::Frame => f.write_str("the driver rejected the frame"),
            SendError::Busy => f.write_str("transmit queue stayed full"),
            SendError::Can(e) => write!(f, "CAN driver: {e:?}"),
        }
    }
}

/// Sends the frames of `msg` on the standard identifier `id`, through a blocking driver.
pub fn send_blocking<C: embedded_can::blocking::Can>(
    can: &mut C,
    id: u16,
    seq: u8,
    msg: &Msg,
) -> Result<(), SendError<C::Error>> {
    let seg = Segmenter::new(msg, seq, Mtu::Classic).map_err(SendError::Encode)?;
    send_segments_blocking(can, id, seg)
}

/// Sends the frames of a [`Segmenter`] (e.g. a secured message, [`Segmenter::sealed`]) on the
/// standard identifier `id`, through a blocking driver.
pub fn send_segments_blocking<C: embedded_can::blocking::Can>(
    can: &mut C,
    id: u16,
    mut seg: Segmenter,
) -> Result<(), SendError<C::Error>> {
    let sid = StandardId::new(id).ok_or(SendError::Frame)?;
    let mut buf = [0u8; 64];
    while let Some(data) = seg.next_frame(&mut buf) {
        let f = C::Frame::new(sid, data).ok_or(SendError::Frame)?;
        can.transmit(&f).map_err(SendError::Can)?;
    }
    Ok(())
}

/// Sends the frames of `msg` on the standard identifier `id` through a non-blocking driver,
/// retrying each frame at most `attempts` times while the driver says `WouldBlock`. A frame the
/// driver displaces from its queue (lower priority) is dropped: our own frames share one
/// identifier, so that never reorders a message.
pub fn send_nb<C: embedded_can::nb::Can>(
    can: &mut C,
    id: u16,
    seq: u8,
    msg: &Msg,
    attempts: u32,
) -> Result<(), SendError<C::Error>> {
    let seg = Segmenter::new(msg, seq, Mtu::Classic).map_err(SendError::Encode)?;
    send_segments_nb(can, id, seg, attempts)
}

/// Sends the frames of a [`Segmenter`] (e.g. a message the device secured,
/// [`Segmenter::device`]) on the standard identifier `id` through a non-blocking driver, as
/// [`send_nb`] does.
pub fn send_segments_nb<C: embedded_can::nb::Can>(
    can: &mut C,
    id: u16,
    mut seg: Segmenter,
    attempts: u32,
) -> Result<(), SendError<C::Error>> {
    let sid = StandardId::new(id).ok_or(SendError::Frame)?;
    let mut buf = [0u8; 64];
    while let Some(data) = seg.next_frame(&mut buf) {
        let f = C::Frame::new(sid, data).ok_or(SendError::Frame)?;
        let mut n = 0u32;
        loop {
            match can.transmit(&f) {
                Ok(_) => break,
                Err(nb::Error::WouldBlock) if n < attempts => n += 1,
                Err(nb::Error::WouldBlock) => return Err(SendError::Busy),
                Err(nb::Error::Other(e)) => return Err(SendError::Can(e)),
            }
        }
    }
    Ok(())
}

/// The standard identifier of a received data frame (`None` for extended or remote frames,
/// which this protocol never uses).
pub fn standard_id<F: embedded_can::Frame>(f: &F) -> Option<u16> {
    match f.id() {
        Id::Standard(s) if !f.is_remote_frame() => Some(s.as_raw()),
        _ => None,
    }
}
