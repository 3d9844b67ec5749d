//! The host end of the CAN protocol: the firmware under QEMU, its UART bridged to TCP, spoken
//! to in SLCAN through the core's own `gough::proto` (never a second implementation).
//!
//! - [`Qemu`] builds (optionally) and starts the firmware with `-serial tcp:127.0.0.1:PORT`.
//! - [`SlcanTcp`] is an `embedded_can::blocking::Can` driver over that socket.
//! - [`Device`] sends messages and collects the answers through `proto::Reassembler`s.
use embedded_can::blocking::Can;
use embedded_can::Frame as _;
use gough::proto::slcan::{self, CanFrame, Decoder, Line};
use gough::proto::{
    crc32, id, link, AckCode, Bytes, Command, Feed, Msg, MsgType, ParamBegin, ParamChunk,
    ParamCommit, Reassembler, Status, CHUNK_LEN, MSG_BUF,
};
use std::io::{Read, Write};
use std::net::{TcpListener, TcpStream};
use std::path::{Path, PathBuf};
use std::process::{Child, Command as Proc, Stdio};
use std::time::{Duration, Instant};

/// The firmware package directory.
pub fn firmware_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../firmware")
}

/// Path of a release firmware binary (`gough-firmware`, `selftest`, ...).
pub fn firmware_elf(bin: &str) -> PathBuf {
    firmware_dir()
        .join("target/thumbv7em-none-eabihf/release")
        .join(bin)
}

/// Builds the firmware binaries (release) with cargo, in the firmware's own workspace.
pub fn build_firmware() -> Result<(), String> {
    let cargo = std::env::var("CARGO").unwrap_or_else(|_| "cargo".into());
    let st = Proc::new(cargo)
        .current_dir(firmware_dir())
        .args(["build", "--release", "--bins"])
        .env_remove("CARGO_TARGET_DIR")
        .status()
        .map_err(|e| format!("cargo build (firmware): {e}"))?;
    if st.success() {
        Ok(())
    } else {
        Err(format!("firmware build failed: {st}"))
    }
}

/// A free local TCP port (bound and released; QEMU binds it right after).
pub fn free_port() -> Result<u16, String> {
    TcpListener::bind("127.0.0.1:0")
        .and_then(|l| l.local_addr())
        .map(|a| a.port())
        .map_err(|e| format!("no free TCP port: {e}"))
}

/// A running QEMU with the firmware; killed on drop unless it exited.
pub struct Qemu {
    child: Child,
    /// TCP port of the bridged UART0.
    pub port: u16,
}

impl Qemu {
    /// Starts `elf` on mps2-an386 with UART0 on a free local TCP port (QEMU waits for the
    /// client before it runs the guest). Semihosting output goes to our stdout/stderr unless
    /// `quiet`; the defmt log goes to `firmware.defmt` in `workdir`.
    /// `port`: the TCP port, or `None` for a free one.
    pub fn start(
        elf: &Path,
        workdir: &Path,
        quiet: bool,
        port: Option<u16>,
    ) -> Result<Qemu, String> {
        if !elf.exists() {
            return Err(format!(
                "{}: no such firmware binary (build it: cargo build --release in firmware/)",
                elf.display()
            ));
        }
        // QEMU runs in `workdir`: make the path absolute first.
        let elf = elf
            .canonicalize()
            .map_err(|e| format!("{}: {e}", elf.display()))?;
        let port = match port {
            Some(p) => p,
            None => free_port()?,
        };
        std::fs::create_dir_all(workdir).map_err(|e| format!("{}: {e}", workdir.display()))?;
        let mut cmd = Proc::new("qemu-system-arm");
        cmd.current_dir(workdir)
            .args(["-cpu", "cortex-m4", "-machine", "mps2-an386"])
            .args(["-display", "none", "-monitor", "none"])
            .args(["-semihosting-config", "enable=on,target=native"])
            .arg("-serial")
            .arg(format!("tcp:127.0.0.1:{port},server=on,wait=on"))
            .arg("-kernel")
            .arg(&elf)
            .stdin(Stdio::null());
        if quiet {
            cmd.stdout(Stdio::null());
        }
        let child = cmd.spawn().map_err(|e| {
            format!("qemu-system-arm: {e} (install it: apt-get install qemu-system-arm)")
        })?;
        Ok(Qemu { child, port })
    }

    /// Waits up to `timeout` for QEMU to exit; its exit code (semihosting), or `None`.
    pub fn wait(&mut self, timeout: Duration) -> Option<i32> {
        let t0 = Instant::now();
        while t0.elapsed() < timeout {
            if let Ok(Some(st)) = self.child.try_wait() {
                return Some(st.code().unwrap_or(-1));
            }
            std::thread::sleep(Duration::from_millis(20));
        }
        None
    }
}

impl Drop for Qemu {
    fn drop(&mut self) {
        if let Ok(None) = self.child.try_wait() {
            let _ = self.child.kill();
            let _ = self.child.wait();
        }
    }
}

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
        }
    }

    /// Sends one message on its identifier; returns the sequence number used.
    pub fn send(&mut self, msg: &Msg) -> Result<u8, String> {
        let cid = id::of(msg.msg_type());
        let k = usize::from(cid == id::CONFIG);
        let seq = self.seq[k];
        self.seq[k] = seq.wrapping_add(1);
        link::send_blocking(&mut self.link, cid, seq, msg).map_err(|e| e.to_string())?;
        Ok(seq)
    }

    /// The next message from the device, waiting at most `timeout`.
    pub fn recv(&mut self, timeout: Duration) -> Result<Msg, String> {
        let deadline = Instant::now() + timeout;
        loop {
            let left = deadline.saturating_duration_since(Instant::now());
            if left.is_zero() {
                return Err("no answer from the device (timed out)".into());
            }
            self.link.timeout = left;
            let f = self.link.receive().map_err(|e| e.to_string())?;
            let now = self.t0.elapsed().as_millis() as u32;
            let fed = match link::standard_id(&f) {
                Some(id::RESULT) => self.rx_result.feed(f.data(), now),
                Some(id::STATUS) => self.rx_status.feed(f.data(), now),
                _ => continue,
            };
            if let Feed::Done(m) = fed {
                return Ok(m);
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
        self.send(&Msg::Command(Command::StatusRequest))?;
        let deadline = Instant::now() + timeout;
        loop {
            let left = deadline.saturating_duration_since(Instant::now());
            if let Msg::Status(s) = self.recv(left)? {
                return Ok(s);
            }
        }
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
