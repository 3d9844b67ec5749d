//! gough firmware, first stage: parses the bundled MF 6.1 tyre at boot (no heap), evaluates the
//! combined-slip Magic Formula in f32 at one operating point, prints it over semihosting and
//! exits with code 0 (1 on any error). The CAN loop arrives with the protocol issue.
#![no_std]
#![no_main]

use cortex_m_rt::{entry, exception, ExceptionFrame};
use cortex_m_semihosting::{debug, hprintln};
use gough::math::Libm;
use gough::mf::{self, Input, Options};

const TYRE: &str = include_str!("../../host-tests/data/tyres/MagicFormula61_Parameters.tir");

#[entry]
fn main() -> ! {
    let code = match run() {
        Ok(()) => debug::EXIT_SUCCESS,
        Err(()) => debug::EXIT_FAILURE,
    };
    debug::exit(code);
    #[allow(clippy::empty_loop)]
    loop {}
}

fn run() -> Result<(), ()> {
    let tyre = gough::tir::parse(TYRE).map_err(|e| hprintln!("tir: {}", e))?;
    let p = tyre.params.cast::<f32>();
    let input = Input {
        fz: 6000.0,
        kappa: -0.05,
        alpha: 0.05,
        gamma: 0.0,
        phit: 0.0,
        vx: 20.0,
        p: None,
    };
    let o = mf::eval::<f32, Libm>(&p, &input, &Options::default()).map_err(|e| hprintln!("mf: {}", e))?;
    hprintln!("Fx {} Fy {} Mz {}", o.fx, o.fy, o.mz);
    Ok(())
}

#[exception]
unsafe fn HardFault(_frame: &ExceptionFrame) -> ! {
    debug::exit(debug::EXIT_FAILURE);
    loop {}
}

#[panic_handler]
fn panic(_info: &core::panic::PanicInfo) -> ! {
    debug::exit(debug::EXIT_FAILURE);
    loop {}
}
