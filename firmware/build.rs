//! Puts the board's memory map where cortex-m-rt's `link.x` finds it: the repository's
//! `memory.x` (QEMU mps2-an386) by default, `boards/stm32f405.x` with the `stm32f4` feature.
use std::{env, fs, path::PathBuf};

fn main() {
    let out = PathBuf::from(env::var_os("OUT_DIR").expect("OUT_DIR"));
    let dir = PathBuf::from(env!("CARGO_MANIFEST_DIR"));
    let memory = if env::var_os("CARGO_FEATURE_STM32F4").is_some() {
        dir.join("boards/stm32f405.x")
    } else {
        dir.join("../memory.x")
    };
    fs::copy(&memory, out.join("memory.x")).expect("copy memory.x");
    println!("cargo:rustc-link-search={}", out.display());
    println!("cargo:rerun-if-changed={}", memory.display());
    println!("cargo:rerun-if-changed=build.rs");
}
