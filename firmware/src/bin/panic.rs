//! Test: a panic exits QEMU with a failure code (the runner sees 1), never hangs.
#![no_std]
#![no_main]

use cortex_m_rt::entry;
use cortex_m_semihosting::hprintln;
use gough_firmware as _; // panic handler, HardFault handler, defmt logger

#[entry]
fn main() -> ! {
    hprintln!("about to panic");
    let v = core::hint::black_box(7u32);
    if v == 7 {
        panic!("deliberate panic ({v})");
    }
    gough_firmware::mps2::exit(true)
}
