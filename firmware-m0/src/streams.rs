// The friction estimator's bench streams, shared by build.rs (which runs them on the host for
// the expected outcome) and the bench (which runs them on the M0): the slalom of
// `firmware/src/workload.rs` on a road of friction `mu` (λμ) with roll camber `camber` [rad],
// as the M4F bench's dry and icy streams.

/// Samples per stream (1 kHz: one slalom period).
pub const SAMPLES: usize = 1000;
/// (λμ, camber amplitude [rad], name) per stream.
pub const STREAMS: [(f32, f32, &str); 2] = [
    (1.0, 0.02, "λμ 1 (dry), camber measured"),
    (0.2, 0.02, "λμ 0.2 (ice), camber measured"),
];
/// FNV-1a offset basis: the hash of no estimate.
pub const HASH0: u32 = 0x811c_9dc5;

/// FNV-1a over an estimate's μ and σ bits, its state and its change flag.
pub fn hash(mut h: u32, e: &gough::mu::Estimate<f32>) -> u32 {
    let words = [
        e.mu.to_bits(),
        e.sigma.to_bits(),
        e.state as u32,
        u32::from(e.change),
    ];
    for w in words {
        for byte in w.to_le_bytes() {
            h ^= u32::from(byte);
            h = h.wrapping_mul(0x0100_0193);
        }
    }
    h
}
