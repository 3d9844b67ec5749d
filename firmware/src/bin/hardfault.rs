//! Test: a HardFault (here an undefined instruction, escalated from UsageFault) exits QEMU with
//! a failure code, never hangs.
#![no_std]
#![no_main]

use cortex_m_rt::entry;
use cortex_m_semihosting::hprintln;
use gough_firmware as _; // panic handler, HardFault handler, defmt logger

#[entry]
fn main() -> ! {
    hprintln!("about to fault");
    cortex_m::asm::udf()
}
