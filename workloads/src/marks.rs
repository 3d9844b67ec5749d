//! Workload markers for outside counters: a bench or profile binary calls [`bench_start`] before
//! a measured workload and [`bench_stop`] after it, each with the workload's id in r0. Exported
//! under these names and never inlined (distinct bodies, so the linker cannot fold them), so a
//! debugger breakpoint or QEMU's execution log (`tools/qemu_profile.py`) finds them.

/// Marks the start of a measured workload (its id in r0).
#[no_mangle]
#[inline(never)]
pub extern "C" fn bench_start(id: u32) {
    core::hint::black_box(id);
    cortex_m::asm::nop();
}

/// Marks the end of a measured workload (its id in r0).
#[no_mangle]
#[inline(never)]
pub extern "C" fn bench_stop(id: u32) {
    core::hint::black_box(id.wrapping_add(0x5700));
    cortex_m::asm::nop();
    cortex_m::asm::nop();
}
