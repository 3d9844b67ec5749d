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
    /// The second-effect round (forward selection): each candidate tried on top of the
    /// verdict's first effect (empty when the verdict is none).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub second: Vec<SecondReport>,
    /// With two effects named: the parameters of both, fitted together on the whole log.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub pair_params: Option<PairParams>,
    /// How the numbers were made.
    pub method: Method,
    /// The friction estimator against the log's `mu` column (when there is one).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub mu: Option<super::mu::MuReport>,
    /// The corrected tyre file (with a verdict): the named effects in SIM.tir's coefficients,
    /// what is left out, and the written file's shrink beside the effect's ([`super::tirfile`]).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub corrected_tir: Option<super::tirfile::TirReport>,
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
    /// The held-out shrink of everything named (`effects`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub shrink: Option<f64>,
    /// The channel it closes most of the gap in (largest reduction in noise units).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub channel: Option<String>,
    /// Effects that explain the data as well (within the blocks' standard error): the data
    /// cannot tell them apart from the verdict.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub indistinguishable_from: Vec<String>,
    /// Every effect named, the first (`effect`) first: one, or two when a second one
    /// significantly improves the held-out fit on top of the first (forward selection).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub effects: Vec<NamedEffect>,
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
    /// How a second effect is sought and when it is named.
    pub second_effect_rule: String,
}

/// One effect of the verdict.
#[derive(Debug, Clone, Serialize)]
pub struct NamedEffect {
    /// Name.
    pub effect: String,
    /// Its held-out shrink alone.
    pub shrink_alone: f64,
    /// Its own share: the held-out shrink of all named effects minus that of the others
    /// without it (with one effect: its shrink alone).
    pub shrink_added: f64,
    /// Significance of what it adds (against the sim for the first, against the first effect
    /// alone for the second).
    pub z_added: f64,
    /// The channel it closes most of the gap in.
    pub channel: String,
    /// Effects that would serve as well in its place.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub indistinguishable_from: Vec<String>,
}

/// A candidate second effect, tried on top of the first.
#[derive(Debug, Clone, Serialize)]
pub struct SecondReport {
    /// Name.
    pub effect: String,
    /// Held-out shrink of the pair.
    pub shrink_pair: f64,
    /// Pair minus the first effect alone.
    pub shrink_added: f64,
    /// Significance of the improvement over the first alone.
    pub z_added: f64,
    /// Named in the verdict.
    pub kept: bool,
}

/// The parameters of a named pair, fitted together on the whole log.
#[derive(Debug, Clone, Serialize)]
pub struct PairParams {
    /// The first effect's.
    pub first: BTreeMap<String, f64>,
    /// The second effect's.
    pub second: BTreeMap<String, f64>,
}
