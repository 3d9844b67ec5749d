//! The report (JSON, `serde_json`): the shape other tools read. See the interface:
//! `baseline`, `where`, `effects`, `verdict`, plus `sim`, `method` and (with a `mu` column) `mu`.

use super::regions::{Channels, Region};
use serde::Serialize;
use std::collections::BTreeMap;

/// The whole report.
#[derive(Debug, Clone, Serialize)]
pub struct Report {
    /// SIM.tir as given.
    pub tir: String,
    /// The log as given.
    pub log: String,
    /// Data rows.
    pub rows: usize,
    /// What the sim is.
    pub sim: SimInfo,
    /// The sim against the log.
    pub baseline: Baseline,
    /// Operating regions holding the gap, largest share first.
    #[serde(rename = "where")]
    pub where_: Vec<Region>,
    /// Every candidate effect, by held-out shrink, largest first.
    pub effects: Vec<EffectReport>,
    /// The diagnosis.
    pub verdict: Verdict,
    /// How the numbers were made.
    pub method: Method,
    /// The friction estimator against the log's `mu` column (when there is one).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub mu: Option<super::mu::MuReport>,
}

/// What the sim is.
#[derive(Debug, Clone, Serialize)]
pub struct SimInfo {
    /// Magic Formula version of SIM.tir.
    pub version: String,
    /// The relaxation-length filters run.
    pub relaxation_filters: bool,
    /// Turn slip is evaluated.
    pub turn_slip: bool,
    /// Where the pressure comes from.
    pub pressure: String,
    /// How the filters are integrated between samples.
    pub hold: String,
}

/// The sim against the log.
#[derive(Debug, Clone, Serialize)]
pub struct Baseline {
    /// RMSE of sim against log per channel \[N, N, N·m\].
    pub rmse: Channels,
    /// Noise floor per channel \[N, N, N·m\].
    pub noise_floor: Channels,
    /// How the noise floor is estimated.
    pub noise_floor_method: String,
}

/// Held-out RMSE before and after an effect.
#[derive(Debug, Clone, Serialize)]
pub struct HeldOut {
    /// The sim.
    pub rmse_before: Channels,
    /// The sim with the effect, each block predicted by parameters fitted on the others.
    pub rmse_after: Channels,
}

/// One candidate effect.
#[derive(Debug, Clone, Serialize)]
pub struct EffectReport {
    /// Name.
    pub effect: String,
    /// Held-out shrink (normalised sum over channels).
    pub shrink: f64,
    /// Its standard error over the cross-validation blocks.
    pub shrink_se: f64,
    /// Significance of the held-out improvement against the noise floor (`method`).
    pub z: f64,
    /// 1 − rmse_after/rmse_before per channel.
    pub shrink_by_channel: Channels,
    /// Held-out RMSE.
    pub heldout: HeldOut,
    /// Parameters fitted on the whole log (`.tir` keys in lower case where they are keys).
    pub params: BTreeMap<String, f64>,
    /// The same parameters in the sim (SIM.tir's values, or the neutral ones).
    pub params_sim: BTreeMap<String, f64>,
    /// Physical form.
    pub form: String,
    /// Was it tried (false: the log cannot show it; see `note`).
    pub applicable: bool,
    /// Why not applicable, or a remark.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub note: Option<String>,
}

/// The verdict.
#[derive(Debug, Clone, Serialize)]
pub struct Verdict {
    /// The effect, or `none`.
    pub effect: String,
    /// Its held-out shrink.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub shrink: Option<f64>,
    /// The channel it closes most of the gap in (largest reduction in noise units).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub channel: Option<String>,
    /// Effects that explain the data as well (within the blocks' standard error): the data
    /// cannot tell them apart from the verdict.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub indistinguishable_from: Vec<String>,
    /// For `none`: the best candidate and why it did not count.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub reason: Option<String>,
}

/// How the numbers were made.
#[derive(Debug, Clone, Serialize)]
pub struct Method {
    /// Cross-validation.
    pub cross_validation: String,
    /// The shrink's definition.
    pub shrink: String,
    /// The verdict's rule and where its threshold comes from.
    pub verdict_rule: String,
    /// The rule for indistinguishable effects.
    pub indistinguishable_rule: String,
}
