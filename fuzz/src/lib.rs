//! What the fuzz targets share: the bundled tyres of the `tir_parse` seed corpus (files of this
//! crate), parsed once.
use gough::mf::Params;
use std::sync::OnceLock;

/// The `.tir` texts: MF 5.2, 6.1 and 6.2, the book's reference tyre, a car tyre.
const TYRES: &[&str] = &[
    include_str!("../corpus/tir_parse/MagicFormula52_Parameters.tir"),
    include_str!("../corpus/tir_parse/MagicFormula61_Parameters.tir"),
    include_str!("../corpus/tir_parse/MagicFormula62_Parameters.tir"),
    include_str!("../corpus/tir_parse/PacejkaBook_Defaults.tir"),
    include_str!("../corpus/tir_parse/mf_185_80R14.tir"),
];

/// Every bundled tyre the reader accepts, in f64.
pub fn tyres() -> &'static [Params<f64>] {
    static P: OnceLock<Vec<Params<f64>>> = OnceLock::new();
    P.get_or_init(|| {
        TYRES
            .iter()
            .filter_map(|t| gough::tir::parse(t).ok().map(|t| t.params))
            .collect()
    })
}

/// The MF 6.1 tyre (`MagicFormula61_Parameters.tir`) in f64 and in f32 (the device's).
pub fn mf61() -> &'static (Params<f64>, Params<f32>) {
    static P: OnceLock<(Params<f64>, Params<f32>)> = OnceLock::new();
    P.get_or_init(|| {
        let text = include_str!("../corpus/tir_parse/MagicFormula61_Parameters.tir");
        let p = gough::tir::parse(text).expect("bundled tyre").params;
        let p32 = p.cast::<f32>();
        (p, p32)
    })
}
