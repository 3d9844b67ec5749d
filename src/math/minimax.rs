//! Minimax polynomial coefficients shared by the fast `f32` kernels (`math::fast`) and the
//! fixed-point kernels (`crate::fixed`): one table, so a refit changes both.
//!
//! Origin: our own Remez fits, `python3 tools/minimax.py` (mpmath), which prints each value and
//! its bit pattern; the script's docstring gives each kernel's form, interval and weight. The
//! fits minimise the *relative* error of the kernel; "fit error" is before rounding to f32.

// sin r = r + r³·(S0 + S1·r² + S2·r⁴), |r| ≤ π/4; fit error 3.9e-9.
pub(crate) const S0: f32 = f32::from_bits(0xbe2aaaa2); // -0.166_666_54
pub(crate) const S1: f32 = f32::from_bits(0x3c088384); // 0.008_332_137
pub(crate) const S2: f32 = f32::from_bits(0xb94c9934); // -0.000_195_120_29

// cos r = 1 − r²/2 + r⁴·(C0 + C1·r²), |r| ≤ π/4; fit error 8.6e-8.
pub(crate) const C0: f32 = f32::from_bits(0x3d2aa4ae); // 0.041_660_957
pub(crate) const C1: f32 = f32::from_bits(0xbab2dd5a); // -0.001_364_629

// tan r = r + r³·(T0 + T1·r² + … + T4·r⁸), |r| ≤ π/4; fit error 2.7e-7.
pub(crate) const T0: f32 = f32::from_bits(0x3eaaad34); // 0.333_352_68
pub(crate) const T1: f32 = f32::from_bits(0x3e0817b5); // 0.132_902_94
pub(crate) const T2: f32 = f32::from_bits(0x3d698d56); // 0.057_019_554
pub(crate) const T3: f32 = f32::from_bits(0x3c50aa07); // 0.012_735_85
pub(crate) const T4: f32 = f32::from_bits(0x3ca654b2); // 0.020_304_058

// atan t = t + t³·(A0 + A1·t² + A2·t⁴ + A3·t⁶), |t| ≤ tan π/8; fit error 2.2e-8.
pub(crate) const A0: f32 = f32::from_bits(0xbeaaaa25); // -0.333_329_35
pub(crate) const A1: f32 = f32::from_bits(0x3e4c90c9); // 0.199_771_06
pub(crate) const A2: f32 = f32::from_bits(0xbe0e0902); // -0.138_706_24
pub(crate) const A3: f32 = f32::from_bits(0x3da470ef); // 0.080_293_53

// asin s = s + s³·(P0 + P1·s² + P2·s⁴ + P3·s⁶), s² ≤ ¼; fit error 9.4e-8.
pub(crate) const P0: f32 = f32::from_bits(0x3e2aa7af); // 0.166_655_29
pub(crate) const P1: f32 = f32::from_bits(0x3d9a75dc); // 0.075_420_11
pub(crate) const P2: f32 = f32::from_bits(0x3d23801f); // 0.039_917_108
pub(crate) const P3: f32 = f32::from_bits(0x3d4dbf12); // 0.050_231_047

// eʳ = 1 + r + r²·(E0 + E1·r + E2·r² + E3·r³), |r| ≤ ln2/2; fit error 1.1e-7.
pub(crate) const E0: f32 = f32::from_bits(0x3efffef4); // 0.499_992_01
pub(crate) const E1: f32 = f32::from_bits(0x3e2aabe4); // 0.166_671_34
pub(crate) const E2: f32 = f32::from_bits(0x3d2b9991); // 0.041_894_5
pub(crate) const E3: f32 = f32::from_bits(0x3c082f43); // 0.008_312_049

// ln(1 + f) = 2s + s³·(L0 + L1·s²), s = f/(2 + f), s² ≤ ((√2 − 1)/(√2 + 1))²; fit error 1.5e-7.
pub(crate) const L0: f32 = f32::from_bits(0x3f2aa348); // 0.666_553_97
pub(crate) const L1: f32 = f32::from_bits(0x3ed30474); // 0.412_143_35
