//! QEMU `mps2-an386` (ARM MPS2 FPGA image AN386: Cortex-M4F at 25 MHz): the CMSDK APB UART0
//! at 0x4000_4000 carrying SLCAN text, SysTick at 1 kHz, semihosting for exit codes, and the
//! defmt global logger (frames written through semihosting to the host file `firmware.defmt`,
//! in QEMU's working directory; decode with `defmt-print -e <elf> < firmware.defmt`).

use core::convert::Infallible;
use core::ptr::addr_of_mut;
use core::sync::atomic::{AtomicBool, AtomicU32, Ordering};
use gough::proto::slcan::{self, CanFrame, Decoder, Line};
use heapless::spsc::{Consumer, Producer, Queue};

/// Base address of UART0 (AN386 TRM, table 3-4).
pub const UART0: usize = 0x4000_4000;
/// SysTick reload for 1 kHz at the 25 MHz system clock.
pub const SYSTICK_RELOAD: u32 = 25_000 - 1;

/// Milliseconds since the SysTick was started (incremented by the SysTick handler).
pub static TICKS: AtomicU32 = AtomicU32::new(0);

/// Starts SysTick at 1 kHz with its interrupt.
pub fn start_systick(mut syst: cortex_m::peripheral::SYST) {
    gough_workloads::clock::start_systick(&mut syst, SYSTICK_RELOAD);
}

/// The SysTick handler's body (each binary declares `#[exception] fn SysTick`): counts the
/// millisecond; returns the new count.
pub fn on_systick() -> u32 {
    TICKS.fetch_add(1, Ordering::Relaxed).wrapping_add(1)
}

/// Priority of the UART0 receive interrupt: above SysTick's, so bytes keep flowing into the
/// receive queue while the tick runs (priorities use the top bits: valid for any number of
/// implemented priority bits ≥ 2).
pub const PRIO_UART: u8 = 0x40;
/// Priority of SysTick (poll and tick run in it): below the UART's, above thread mode.
pub const PRIO_SYSTICK: u8 = 0xC0;

/// Sets the priorities [`PRIO_UART`] and [`PRIO_SYSTICK`].
pub fn set_priorities(scb: &mut cortex_m::peripheral::SCB, nvic: &mut cortex_m::peripheral::NVIC) {
    use cortex_m::peripheral::scb::SystemHandler;
    // SAFETY: changing priorities can break priority-based critical sections; this firmware
    // uses none (its critical sections mask interrupts), and both handlers are ready.
    unsafe {
        scb.set_priority(SystemHandler::SysTick, PRIO_SYSTICK);
        nvic.set_priority(Irq(UART0_RX_IRQ as u16), PRIO_UART);
    }
}

/// The CMSDK APB UART (ARM DDI 0479, §4.3): 1-byte buffers each way; receive by interrupt.
pub struct Uart {
    base: usize,
}

const DATA: usize = 0x00;
const STATE: usize = 0x04;
const CTRL: usize = 0x08;
const INTSTATUS: usize = 0x0C;
const BAUDDIV: usize = 0x10;
const STATE_TXFULL: u32 = 1;
const STATE_RXFULL: u32 = 2;
const CTRL_TX_EN: u32 = 1;
const CTRL_RX_EN: u32 = 2;
const CTRL_RX_INTEN: u32 = 8;
const INT_RX: u32 = 2;
/// UART0 receive interrupt number on mps2-an386 (QEMU `hw/arm/mps2.c`: UART0 RX = IRQ 0).
const UART0_RX_IRQ: i16 = 0;

impl Uart {
    fn rd(&self, off: usize) -> u32 {
        // SAFETY: a register of the UART this value owns.
        unsafe { ((self.base + off) as *const u32).read_volatile() }
    }
    fn wr(&self, off: usize, v: u32) {
        // SAFETY: as above.
        unsafe { ((self.base + off) as *mut u32).write_volatile(v) }
    }
    /// Sends bytes, waiting while the transmit buffer is full.
    pub fn write(&mut self, bytes: &[u8]) {
        for &b in bytes {
            while self.rd(STATE) & STATE_TXFULL != 0 {}
            self.wr(DATA, u32::from(b));
        }
    }
}

/// Receive queue: UART0 RX interrupt → main loop (single producer, single consumer).
const RXQ_LEN: usize = 2048;
static mut RXQ: Queue<u8, RXQ_LEN> = Queue::new();
static mut RX_PRODUCER: Option<Producer<'static, u8>> = None;
/// Set when the queue was full: the interrupt is off and the byte waits in the UART, so QEMU
/// holds back further input (lossless flow control) until the main loop has made room.
static RX_PAUSED: AtomicBool = AtomicBool::new(false);

/// Moves received bytes from UART0 into the queue. Runs in the RX interrupt, or in a critical
/// section of the main loop (so the producer has one user at a time).
fn rx_pump() {
    let uart = Uart { base: UART0 };
    // SAFETY: the producer is used only here, with interrupts excluded or from the ISR.
    let Some(prod) = (unsafe { (*addr_of_mut!(RX_PRODUCER)).as_mut() }) else {
        return;
    };
    uart.wr(INTSTATUS, INT_RX);
    while uart.rd(STATE) & STATE_RXFULL != 0 {
        if !prod.ready() {
            uart.wr(CTRL, CTRL_TX_EN | CTRL_RX_EN);
            RX_PAUSED.store(true, Ordering::SeqCst);
            return;
        }
        let _ = prod.enqueue(uart.rd(DATA) as u8);
    }
}

/// All device interrupts land here (cortex-m-rt without a PAC); UART0 RX is the one enabled.
#[cortex_m_rt::exception]
unsafe fn DefaultHandler(irqn: i16) {
    if irqn == UART0_RX_IRQ {
        rx_pump();
    }
}

#[derive(Clone, Copy)]
struct Irq(u16);
// SAFETY: an interrupt number of this board.
unsafe impl cortex_m::interrupt::InterruptNumber for Irq {
    fn number(self) -> u16 {
        self.0
    }
}

/// CAN over SLCAN text on UART0, as an `embedded_can::nb::Can` driver.
pub struct SlcanPort {
    uart: Uart,
    rx: Consumer<'static, u8>,
    dec: Decoder,
    /// Lines that were not SLCAN (garbage on the UART).
    pub errors: u32,
}

/// No error is reported through the driver: bad lines are counted in [`SlcanPort::errors`].
#[derive(Debug, Clone, Copy)]
pub struct NoError(Infallible);

impl embedded_can::Error for NoError {
    fn kind(&self) -> embedded_can::ErrorKind {
        embedded_can::ErrorKind::Other
    }
}

impl SlcanPort {
    /// Takes UART0: enables it with its receive interrupt. Returns `None` if called twice.
    pub fn take_uart0() -> Option<Self> {
        static TAKEN: AtomicBool = AtomicBool::new(false);
        if TAKEN.swap(true, Ordering::SeqCst) {
            return None;
        }
        // SAFETY: runs once (TAKEN); the queue is split before the interrupt is enabled.
        let rx = unsafe {
            let (p, c) = (*addr_of_mut!(RXQ)).split();
            *addr_of_mut!(RX_PRODUCER) = Some(p);
            c
        };
        let uart = Uart { base: UART0 };
        uart.wr(BAUDDIV, 16);
        uart.wr(CTRL, CTRL_TX_EN | CTRL_RX_EN | CTRL_RX_INTEN);
        // SAFETY: the handler (DefaultHandler) is ready and shares nothing unsynchronised.
        unsafe { cortex_m::peripheral::NVIC::unmask(Irq(UART0_RX_IRQ as u16)) };
        Some(SlcanPort {
            uart,
            rx,
            dec: Decoder::new(),
            errors: 0,
        })
    }

    fn next_byte(&mut self) -> Option<u8> {
        let b = self.rx.dequeue();
        if RX_PAUSED.load(Ordering::SeqCst) {
            cortex_m::interrupt::free(|_| {
                RX_PAUSED.store(false, Ordering::SeqCst);
                self.uart.wr(CTRL, CTRL_TX_EN | CTRL_RX_EN | CTRL_RX_INTEN);
                rx_pump();
            });
        }
        b
    }

    /// `true` when received bytes wait to be decoded.
    pub fn rx_pending(&self) -> bool {
        self.rx.ready()
    }
}

impl embedded_can::nb::Can for SlcanPort {
    type Frame = CanFrame;
    type Error = NoError;

    fn transmit(&mut self, frame: &CanFrame) -> nb::Result<Option<CanFrame>, NoError> {
        let mut line = [0u8; slcan::MAX_LINE];
        self.uart.write(slcan::encode(frame, &mut line));
        Ok(None)
    }

    fn receive(&mut self) -> nb::Result<CanFrame, NoError> {
        while let Some(b) = self.next_byte() {
            match self.dec.push(b) {
                None | Some(Ok(Line::Empty | Line::Bell)) => {}
                Some(Ok(Line::Frame(f))) => return Ok(f),
                // Lawicel commands: answer version/serial/flags, acknowledge the others.
                Some(Ok(Line::Command(c))) => self.uart.write(match c {
                    b'V' => b"V1013\r".as_slice(),
                    b'v' => b"v0200\r",
                    b'N' => b"NGOUG\r",
                    b'F' => b"F00\r",
                    _ => b"\r",
                }),
                Some(Err(_)) => {
                    self.errors = self.errors.wrapping_add(1);
                    self.uart.write(b"\x07");
                }
            }
        }
        Err(nb::Error::WouldBlock)
    }
}

/// Exits QEMU with a status (semihosting); never returns.
pub fn exit(ok: bool) -> ! {
    use cortex_m_semihosting::debug;
    debug::exit(if ok {
        debug::EXIT_SUCCESS
    } else {
        debug::EXIT_FAILURE
    });
    #[allow(clippy::empty_loop)]
    loop {}
}

/// Panics print their message through semihosting and exit QEMU with failure, never hang.
#[panic_handler]
fn panic(info: &core::panic::PanicInfo) -> ! {
    cortex_m::interrupt::disable();
    cortex_m_semihosting::hprintln!("panicked: {}", info);
    exit(false)
}

/// A HardFault (bus error, undefined instruction, escalated fault) exits QEMU with failure.
#[cortex_m_rt::exception]
unsafe fn HardFault(frame: &cortex_m_rt::ExceptionFrame) -> ! {
    cortex_m_semihosting::hprintln!("HardFault at pc {:#010x}", frame.pc());
    exit(false)
}

/// Where the device key is provisioned at flash time: the last 256 bytes of SSRAM1 (the
/// "flash", outside the image: `memory.x`), a [`gough::proto::auth::slot`] (28 bytes).
/// `gough firmware run --key-file KEY` writes it with QEMU's `-device loader`; without it the
/// slot reads as zeros: no key, and the device refuses every state-changing message.
pub const KEY_SLOT: usize = 0x003F_FF00;

/// The key provisioned in [`KEY_SLOT`], if any, its MAC length and what it authenticates.
pub fn provisioned_key() -> Option<(
    gough::proto::Key,
    gough::proto::MacLen,
    gough::proto::Policy,
)> {
    // SAFETY: KEY_SLOT is mapped memory (SSRAM1, 4 MB) that nothing else writes.
    let s =
        unsafe { core::ptr::read_volatile(KEY_SLOT as *const [u8; gough::proto::auth::slot::LEN]) };
    gough::proto::auth::slot::decode(&s)
}

/// The board's non-volatile boot counter (the epoch of `gough::proto::auth`), raised and stored
/// by one call per boot: the host file `gough-nv.bin` in QEMU's working directory, through
/// semihosting (this board's stand-in for a flash page; 8 bytes: the value and its CRC-32).
/// Returns the new value, or `None` when it cannot be read back intact or stored (the device
/// then runs without a key: freshness across resets could not be promised).
pub fn next_epoch() -> Option<u32> {
    use cortex_m_semihosting::{nr, syscall};
    const NAME: &[u8] = b"gough-nv.bin\0";
    let open = |mode: usize| {
        // SAFETY: SYS_OPEN with a NUL-terminated name and its length without the NUL.
        let fd = unsafe { syscall!(OPEN, NAME.as_ptr(), mode, NAME.len() - 1) };
        (fd as isize >= 0).then_some(fd)
    };
    let mut rec = [0u8; 8];
    let old = match open(nr::open::R_BINARY) {
        // No file yet: the first boot.
        None => 0,
        Some(fd) => {
            // SAFETY: SYS_READ into a live buffer from an open host file; returns the bytes not read.
            let left = unsafe { syscall!(READ, fd, rec.as_mut_ptr(), rec.len()) };
            // SAFETY: SYS_CLOSE of the handle opened above.
            unsafe { syscall!(CLOSE, fd) };
            let (v, c) = rec.split_at(4);
            let v = u32::from_le_bytes(v.try_into().ok()?);
            if left != 0 || gough::proto::crc32(&v.to_le_bytes()).to_le_bytes() != c {
                return None;
            }
            v
        }
    };
    let new = old.checked_add(1)?;
    let (v, c) = rec.split_at_mut(4);
    v.copy_from_slice(&new.to_le_bytes());
    c.copy_from_slice(&gough::proto::crc32(&new.to_le_bytes()).to_le_bytes());
    let fd = open(nr::open::W_TRUNC_BINARY)?;
    // SAFETY: SYS_WRITE of a live buffer to an open host file; returns the bytes not written.
    let left = unsafe { syscall!(WRITE, fd, rec.as_ptr(), rec.len()) };
    // SAFETY: SYS_CLOSE of the handle opened above.
    unsafe { syscall!(CLOSE, fd) };
    (left == 0).then_some(new)
}

/// Stores the epoch after a counter wrap ([`gough::proto::Verifier`] moved to the next one):
/// [`next_epoch`] stores the value above the stored one, which is this one when the stored one
/// is one below. `false` if it could not be stored.
pub fn store_epoch(epoch: u32) -> bool {
    next_epoch() == Some(epoch)
}

mod logger {
    //! defmt global logger: frames to the semihosting host file `firmware.defmt`.
    use core::sync::atomic::{AtomicBool, AtomicIsize, Ordering};
    use cortex_m_semihosting::{nr, syscall};

    #[defmt::global_logger]
    struct Logger;

    static TAKEN: AtomicBool = AtomicBool::new(false);
    static mut CS: critical_section::RestoreState = critical_section::RestoreState::invalid();
    static mut ENCODER: defmt::Encoder = defmt::Encoder::new();
    /// Host file handle: -2 not opened yet, -1 could not open.
    static FD: AtomicIsize = AtomicIsize::new(-2);

    fn write(bytes: &[u8]) {
        let mut fd = FD.load(Ordering::Relaxed);
        if fd == -2 {
            const NAME: &[u8] = b"firmware.defmt\0";
            // SAFETY: SYS_OPEN with a NUL-terminated name and its length without the NUL.
            fd = unsafe {
                syscall!(
                    OPEN,
                    NAME.as_ptr(),
                    nr::open::W_TRUNC_BINARY,
                    NAME.len() - 1
                )
            } as isize;
            FD.store(fd, Ordering::Relaxed);
        }
        if fd >= 0 {
            // SAFETY: SYS_WRITE of a live buffer to an open host file.
            unsafe { syscall!(WRITE, fd as usize, bytes.as_ptr(), bytes.len()) };
        }
    }

    // SAFETY (all four): defmt's contract: acquire/release pair up, `write` and `flush` run
    // between them, inside the critical section taken in `acquire`.
    unsafe impl defmt::Logger for Logger {
        fn acquire() {
            let restore = unsafe { critical_section::acquire() };
            if TAKEN.swap(true, Ordering::Relaxed) {
                super::exit(false); // re-entrant logging is a bug: fail loudly
            }
            unsafe {
                CS = restore;
                (*core::ptr::addr_of_mut!(ENCODER)).start_frame(write);
            }
        }
        unsafe fn flush() {}
        unsafe fn release() {
            (*core::ptr::addr_of_mut!(ENCODER)).end_frame(write);
            TAKEN.store(false, Ordering::Relaxed);
            critical_section::release(CS);
        }
        unsafe fn write(bytes: &[u8]) {
            (*core::ptr::addr_of_mut!(ENCODER)).write(bytes, write);
        }
    }

    #[defmt::panic_handler]
    fn defmt_panic() -> ! {
        super::exit(false)
    }
}
