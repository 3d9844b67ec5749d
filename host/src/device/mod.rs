//! The host end of the CAN protocol: the firmware under QEMU, its UART bridged to TCP, spoken
//! to in SLCAN through the core's own `gough::proto` (never a second implementation).
//!
//! - [`qemu`]: the firmware images under QEMU — [`Qemu`] starts the firmware with
//!   `-serial tcp:127.0.0.1:PORT`; [`qemu::run`] runs a bench or test image to its exit.
//! - [`SlcanTcp`] is an `embedded_can::blocking::Can` driver over that socket.
//! - [`Device`] sends messages and collects the answers through `proto::Reassembler`s.
use embedded_can::blocking::Can;
use embedded_can::Frame as _;
use gough::proto::slcan::{self, CanFrame, Decoder, Line};
use gough::proto::{
    auth, crc32, id, link, AckCode, Bytes, Command, Feed, Key, MacLen, Msg, MsgType, Mtu,
    ParamBegin, ParamChunk, ParamCommit, Policy, Reassembler, Segmenter, Signer, Status, Verifier,
    CHUNK_LEN, MSG_BUF,
};
use std::io::{Read, Write};
use std::net::TcpStream;
use std::time::{Duration, Instant};

pub mod qemu;
pub use qemu::{build_firmware, firmware_dir, firmware_elf, free_port, Qemu};

/// Why the link failed.
#[derive(Debug)]
pub enum LinkError {
    /// Socket error.
    Io(std::io::Error),
    /// Nothing arrived in time.
    Timeout,
    /// The peer closed the connection.
    Closed,
}

impl embedded_can::Error for LinkError {
    fn kind(&self) -> embedded_can::ErrorKind {
        embedded_can::ErrorKind::Other
    }
}

impl std::fmt::Display for LinkError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            LinkError::Io(e) => write!(f, "socket: {e}"),
            LinkError::Timeout => f.write_str("timed out"),
            LinkError::Closed => f.write_str("connection closed"),
        }
    }
}

/// SLCAN over a TCP socket, as a blocking `embedded_can` driver.
pub struct SlcanTcp {
    stream: TcpStream,
    dec: Decoder,
    buf: Vec<u8>,
    pos: usize,
    /// Lines that were not SLCAN.
    pub bad_lines: u64,
    /// Timeout of one `receive`.
    pub timeout: Duration,
}

impl SlcanTcp {
    /// Connects to `127.0.0.1:port`, retrying for up to `patience`.
    pub fn connect(port: u16, patience: Duration) -> Result<SlcanTcp, String> {
        let t0 = Instant::now();
        loop {
            match TcpStream::connect(("127.0.0.1", port)) {
                Ok(stream) => {
                    let _ = stream.set_nodelay(true);
                    return Ok(SlcanTcp {
                        stream,
                        dec: Decoder::new(),
                        buf: Vec::new(),
                        pos: 0,
                        bad_lines: 0,
                        timeout: Duration::from_secs(10),
                    });
                }
                Err(e) if t0.elapsed() > patience => {
                    return Err(format!("connect to 127.0.0.1:{port}: {e}"))
                }
                Err(_) => std::thread::sleep(Duration::from_millis(50)),
            }
        }
    }

    /// Writes raw bytes (for tests that send garbage).
    pub fn write_raw(&mut self, bytes: &[u8]) -> std::io::Result<()> {
        self.stream.write_all(bytes)
    }

    fn next_byte(&mut self, deadline: Instant) -> Result<u8, LinkError> {
        if self.pos >= self.buf.len() {
            let left = deadline.saturating_duration_since(Instant::now());
            if left.is_zero() {
                return Err(LinkError::Timeout);
            }
            self.stream
                .set_read_timeout(Some(left))
                .map_err(LinkError::Io)?;
            self.buf.resize(4096, 0);
            match self.stream.read(&mut self.buf) {
                Ok(0) => return Err(LinkError::Closed),
                Ok(n) => {
                    self.buf.truncate(n);
                    self.pos = 0;
                }
                Err(e)
                    if matches!(
                        e.kind(),
                        std::io::ErrorKind::WouldBlock | std::io::ErrorKind::TimedOut
                    ) =>
                {
                    self.buf.clear();
                    return Err(LinkError::Timeout);
                }
                Err(e) => return Err(LinkError::Io(e)),
            }
        }
        let b = self.buf.get(self.pos).copied().ok_or(LinkError::Timeout)?;
        self.pos += 1;
        Ok(b)
    }
}

impl Can for SlcanTcp {
    type Frame = CanFrame;
    type Error = LinkError;

    fn transmit(&mut self, frame: &CanFrame) -> Result<(), LinkError> {
        let mut line = [0u8; slcan::MAX_LINE];
        self.stream
            .write_all(slcan::encode(frame, &mut line))
            .map_err(LinkError::Io)
    }

    fn receive(&mut self) -> Result<CanFrame, LinkError> {
        let deadline = Instant::now() + self.timeout;
        loop {
            let b = self.next_byte(deadline)?;
            match self.dec.push(b) {
                Some(Ok(Line::Frame(f))) => return Ok(f),
                Some(Err(_)) => self.bad_lines += 1,
                _ => {}
            }
        }
    }
}

/// A device on the other end of a [`SlcanTcp`] link.
pub struct Device {
    /// The link.
    pub link: SlcanTcp,
    rx_result: Reassembler<MSG_BUF>,
    rx_status: Reassembler<MSG_BUF>,
    seq: [u8; 2],
    t0: Instant,
    /// Secures the state-changing messages [`Device::send`] sends ([`Device::authenticate`]);
    /// every message when [`Device::answers`] is set.
    pub signer: Option<Signer>,
    /// Checks every answer of a device provisioned with [`Policy::All`]
    /// ([`Device::authenticate_all`]): an answer it refuses (forged, stale, unsigned) is counted
    /// in its status and never returned by [`Device::recv`].
    pub answers: Option<Verifier>,
}

/// The key of a key file (32 hexadecimal digits; `#` comment lines allowed).
pub fn read_key(path: &std::path::Path) -> Result<Key, String> {
    let text = std::fs::read_to_string(path).map_err(|e| format!("{}: {e}", path.display()))?;
    Key::from_hex(&text).ok_or_else(|| {
        format!(
            "{}: not a key file (32 hexadecimal digits on one line)",
            path.display()
        )
    })
}

impl Device {
    /// Wraps a connected link.
    pub fn new(link: SlcanTcp) -> Device {
        Device {
            link,
            rx_result: Reassembler::new(),
            rx_status: Reassembler::new(),
            seq: [0; 2],
            t0: Instant::now(),
            signer: None,
            answers: None,
        }
    }

    /// Requests the device's `Status` (the unsecured status request) and waits up to `timeout`
    /// for it: the status and its encoded bytes (whether they carry a MAC).
    fn status_raw(&mut self, timeout: Duration) -> Result<(Status, Vec<u8>), String> {
        self.send(&Msg::Command(Command::StatusRequest))?;
        let deadline = Instant::now() + timeout;
        loop {
            let left = deadline.saturating_duration_since(Instant::now());
            if let (Msg::Status(s), bytes) = self.recv_raw(left)? {
                return Ok((s, bytes));
            }
        }
    }

    /// Signs from now on with `key`: reads the device's status for its MAC length, epoch and
    /// highest accepted counter (`Status::auth`). Fails when the device has no key, or signs
    /// its answers (then every message must be signed: [`Device::authenticate_all`]).
    pub fn authenticate(&mut self, key: Key) -> Result<(), String> {
        self.answers = None;
        let (s, bytes) = self.status_raw(Duration::from_secs(20))?;
        let s = s.auth;
        if matches!(Msg::decode_secured(&bytes), Ok((_, Some(_)))) {
            return Err(
                "the device authenticates every message (provisioned with --secure-all): \
                        sign with --secure-all"
                    .into(),
            );
        }
        let mac_len = MacLen::new(s.mac_len)
            .ok_or("the device has no key: it refuses every state-changing message")?;
        self.signer = Some(Signer::new(key, mac_len, s.epoch, s.counter));
        Ok(())
    }

    /// Signs everything from now on with `key`, for a device provisioned with [`Policy::All`]
    /// (`gough firmware run --secure-all`): the status request (unsecured: the freshness
    /// synchronisation) brings a signed `Status`, whose MAC under the key and the epoch it states
    /// is checked; its MAC length, epoch and counter start the signer, its own counter the
    /// checking of the device's answers ([`Device::answers`]). Fails when the device has no key,
    /// does not sign its answers, or its `Status` does not verify (another key).
    pub fn authenticate_all(&mut self, key: Key) -> Result<(), String> {
        self.signer = None;
        self.answers = None;
        let (s, bytes) = self.status_raw(Duration::from_secs(20))?;
        let mac_len = MacLen::new(s.auth.mac_len)
            .ok_or("the device has no key: it refuses every state-changing message")?;
        let (_, trailer) = Msg::decode_secured(&bytes).map_err(|e| e.to_string())?;
        let t = trailer
            .ok_or("the device does not sign its answers (provisioned without --secure-all)")?;
        let mut v = Verifier::new(key, mac_len, s.auth.epoch).with_policy(Policy::All);
        v.set_counter(t.counter.saturating_sub(1));
        v.check(id::STATUS, &Msg::Status(s), &bytes).map_err(|r| {
            format!(
                "the device's status does not verify ({:?}): another key?",
                r.code
            )
        })?;
        self.signer = Some(Signer::new(key, mac_len, s.auth.epoch, s.auth.counter));
        self.answers = Some(v);
        Ok(())
    }

    /// Sends one message on its identifier, secured when it changes the device's state and a
    /// signer is set ([`Device::authenticate`]), or always once the answers are checked too
    /// ([`Device::authenticate_all`]); returns the sequence number used.
    pub fn send(&mut self, msg: &Msg) -> Result<u8, String> {
        let cid = id::of(msg.msg_type());
        let k = usize::from(cid == id::CONFIG);
        let seq = self.seq[k];
        self.seq[k] = seq.wrapping_add(1);
        let all = self.answers.is_some();
        let seg = match self.signer.as_mut() {
            Some(s) if all || auth::is_state_changing(msg) => {
                Segmenter::sealed(msg, seq, Mtu::Classic, s)
            }
            _ => Segmenter::new(msg, seq, Mtu::Classic),
        }
        .map_err(|e| e.to_string())?;
        link::send_segments_blocking(&mut self.link, cid, seg).map_err(|e| e.to_string())?;
        Ok(seq)
    }

    /// The next message from the device, waiting at most `timeout`. When the answers are
    /// checked ([`Device::answers`]) one that does not verify is counted there and skipped.
    pub fn recv(&mut self, timeout: Duration) -> Result<Msg, String> {
        self.recv_raw(timeout).map(|(m, _)| m)
    }

    /// As [`Device::recv`], with the message's encoded bytes.
    pub fn recv_raw(&mut self, timeout: Duration) -> Result<(Msg, Vec<u8>), String> {
        let deadline = Instant::now() + timeout;
        loop {
            let left = deadline.saturating_duration_since(Instant::now());
            if left.is_zero() {
                return Err("no answer from the device (timed out)".into());
            }
            self.link.timeout = left;
            let f = self.link.receive().map_err(|e| e.to_string())?;
            let now = self.t0.elapsed().as_millis() as u32;
            let (cid, rx) = match link::standard_id(&f) {
                Some(id::RESULT) => (id::RESULT, &mut self.rx_result),
                Some(id::STATUS) => (id::STATUS, &mut self.rx_status),
                _ => continue,
            };
            if let Feed::Done(m) = rx.feed(f.data(), now) {
                if let Some(v) = self.answers.as_mut() {
                    if let Err(r) = v.check(cid, &m, rx.last()) {
                        eprintln!("answer refused: {:?} {:?} on {cid:#x}", r.of, r.code);
                        continue;
                    }
                }
                return Ok((m, rx.last().to_vec()));
            }
        }
    }

    /// Frames and drops seen from the device's side of the bus (result + status identifiers).
    pub fn rx_counters(&self) -> gough::proto::Counters {
        let mut c = *self.rx_result.counters();
        c.add(self.rx_status.counters());
        c
    }

    /// Waits for an `Ack` of a request type, skipping other messages.
    pub fn wait_ack(&mut self, of: MsgType, timeout: Duration) -> Result<AckCode, String> {
        let deadline = Instant::now() + timeout;
        loop {
            let left = deadline.saturating_duration_since(Instant::now());
            match self.recv(left)? {
                Msg::Ack(a) if a.of == of as u8 => return Ok(a.code),
                _ => continue,
            }
        }
    }

    /// Asks for and returns the device's status.
    pub fn status(&mut self, timeout: Duration) -> Result<Status, String> {
        self.status_raw(timeout).map(|(s, _)| s)
    }

    /// Uploads a `.tir` text: begin (acknowledged), chunks, commit (acknowledged). The device
    /// parses and validates it before use; its error comes back as a message naming the line.
    pub fn upload_tir(&mut self, text: &[u8]) -> Result<u32, String> {
        let hash = crc32(text);
        let len = u32::try_from(text.len()).map_err(|_| "tyre file too long")?;
        self.send(&Msg::ParamBegin(ParamBegin { len, hash }))?;
        match self.wait_ack(MsgType::ParamBegin, Duration::from_secs(10))? {
            AckCode::Ok => {}
            c => return Err(format!("device refused the upload: {c:?}")),
        }
        for (i, c) in text.chunks(CHUNK_LEN).enumerate() {
            let data = Bytes::new(c).ok_or("chunk too long")?;
            let offset = (i * CHUNK_LEN) as u32;
            self.send(&Msg::ParamChunk(ParamChunk { offset, data }))?;
        }
        self.send(&Msg::ParamCommit(ParamCommit { hash }))?;
        match self.wait_ack(MsgType::ParamCommit, Duration::from_secs(30))? {
            AckCode::Ok => Ok(hash),
            AckCode::TirError { line } => {
                Err(format!("the device rejected the tyre file at line {line}"))
            }
            c => Err(format!("upload failed: {c:?}")),
        }
    }

    /// Sends `Command::Stop` and returns the final status.
    pub fn stop(&mut self, timeout: Duration) -> Result<Status, String> {
        self.send(&Msg::Command(Command::Stop))?;
        let deadline = Instant::now() + timeout;
        loop {
            let left = deadline.saturating_duration_since(Instant::now());
            if let Msg::Status(s) = self.recv(left)? {
                return Ok(s);
            }
        }
    }
}
