//! Stack painting: fill the free stack with a pattern at boot, later find the deepest word that
//! was overwritten. Measures the worst stack use of everything that ran in between (main loop,
//! exceptions, interrupts), to the word.

use core::ptr::{addr_of, addr_of_mut};

const PAINT: u32 = 0xCCCC_CCCC;

extern "C" {
    // cortex-m-rt's linker script: the stack grows down from `_stack_start` to `_stack_end`
    // (the end of .bss/.uninit, unless the board's memory.x sets both: the STM32F405's CCM).
    static mut _stack_end: u32;
    static _stack_start: u32;
}

/// Paints from the bottom of the stack up to 256 bytes below the current stack pointer.
///
/// # Safety
/// Call once, early in `main`, before anything uses the region below the current frame.
pub unsafe fn paint() {
    let sp = cortex_m::register::msp::read() as usize;
    let mut p = addr_of_mut!(_stack_end);
    while (p as usize) + 256 < sp {
        p.write_volatile(PAINT);
        p = p.add(1);
    }
}

/// Deepest stack use since [`paint`] \[bytes\].
pub fn peak() -> u32 {
    // SAFETY: reads words of the stack region below the live frames: painted or already used.
    unsafe {
        let top = addr_of!(_stack_start) as usize;
        let mut p: *const u32 = addr_of!(_stack_end);
        while (p as usize) < top && p.read_volatile() == PAINT {
            p = p.add(1);
        }
        (top - p as usize) as u32
    }
}
