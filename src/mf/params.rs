//! Magic Formula parameter sets: one field per `.tir` key, named as the key in lower case.
//!
//! The table in this file is the single source of the key names: it generates [`Params`], the
//! [`Key`] enum (variants spelled exactly as in `.tir` files, so a grep finds both), each key's
//! [`Need`] (required, scaling factor, extension, range limit, turn slip) and the versions that
//! read it. The `.tir` reader ([`crate::tir`]) and every equation use it.
//!
//! Units: SI (N, m, rad, Pa, s), axes ISO-W (TYDEX W) as in `.tir` files. Parameters `p`, `q`,
//! `r`, `s` are non-dimensional (paper, appendix); λ (`l*`) scaling factors default to 1.

use crate::math::{Float, Real};

/// Magic Formula version, from `FITTYP`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Version {
    /// Delft Tyre 96, the steady-state model of the paper's appendix (eqs. 22–75). TNO's
    /// MF-Tyre 5.0 files (`FITTYP = 5`) carry exactly this parameter set and are evaluated with it.
    Delft96,
    /// MF-Tyre 5.2 (`FITTYP = 6` or `21`), and ADAMS PAC2002 files, which carry no `FITTYP`.
    Mf52,
    /// MF-Tyre 6.1 (`FITTYP = 61`): adds inflation pressure, turn slip, the full Mx/My.
    Mf61,
    /// MF-Tyre 6.2 (`FITTYP = 62`): the forces and moments of 6.1; differs in the vertical and
    /// loaded-radius model, which this crate does not evaluate (see README.md, "What it does not").
    Mf62,
}

impl Version {
    /// The version of a `FITTYP` value, if supported.
    pub const fn from_fittyp(fittyp: i64) -> Option<Version> {
        match fittyp {
            5 => Some(Version::Delft96),
            6 | 21 => Some(Version::Mf52),
            61 => Some(Version::Mf61),
            62 => Some(Version::Mf62),
            _ => None,
        }
    }
    /// `true` for MF 6.1 and 6.2 (pressure, turn slip, MF 6 camber formulation).
    pub const fn is_mf6(self) -> bool {
        matches!(self, Version::Mf61 | Version::Mf62)
    }
    /// Human-readable name.
    pub const fn name(self) -> &'static str {
        match self {
            Version::Delft96 => "Delft Tyre 96 / MF-Tyre 5.0",
            Version::Mf52 => "MF-Tyre 5.2",
            Version::Mf61 => "MF-Tyre 6.1",
            Version::Mf62 => "MF-Tyre 6.2",
        }
    }
}

/// Side of the vehicle a tyre was measured on (`TYRESIDE`), or is mounted on.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Side {
    /// Left side of the vehicle.
    Left,
    /// Right side of the vehicle.
    Right,
}

/// How a key is treated when a `.tir` file does not give it.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Need {
    /// Required by the versions that read it: a missing key is an error.
    Required,
    /// User scaling factor λ: defaults to 1 (paper: "The default value of these factors is set
    /// equal to one").
    Scale,
    /// Extension coefficient (combined-slip refinement, overturning/rolling moment, relaxation,
    /// ...): absent means "effect not modelled", taken as 0 and reported as a warning.
    Extension,
    /// Range of validity of an input: absent means "no limit", reported as a warning.
    Range,
    /// Turn-slip coefficient (MF 6.x): absent makes turn-slip evaluation unavailable.
    TurnSlip,
}

/// Which versions read a key.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Since {
    /// Every version (Delft Tyre 96 onwards).
    All,
    /// MF-Tyre 5.2 and 6.x only.
    Mf52,
    /// MF-Tyre 5.x only (dropped in 6.x).
    Mf5Only,
    /// MF-Tyre 6.x only.
    Mf6,
}

impl Since {
    /// Does `version` read a key of this kind?
    pub const fn covers(self, version: Version) -> bool {
        match self {
            Since::All => true,
            Since::Mf52 => !matches!(version, Version::Delft96),
            Since::Mf5Only => !version.is_mf6(),
            Since::Mf6 => version.is_mf6(),
        }
    }
}

macro_rules! tir_params {
    ($( $key:ident $field:ident $need:ident $since:ident $doc:literal ;)*) => {
        /// A `.tir` key this crate knows, spelled exactly as in the file (upper case).
        #[allow(non_camel_case_types, clippy::upper_case_acronyms)]
        #[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
        #[cfg_attr(feature = "defmt", derive(defmt::Format))]
        #[non_exhaustive]
        pub enum Key { $( #[doc = $doc] $key, )* }

        impl Key {
            /// Every key, in table order.
            pub const ALL: &'static [Key] = &[ $( Key::$key, )* ];
            /// The key as written in `.tir` files.
            pub const fn name(self) -> &'static str {
                match self { $( Key::$key => stringify!($key), )* }
            }
            /// What happens when a file does not give this key.
            pub const fn need(self) -> Need {
                match self { $( Key::$key => Need::$need, )* }
            }
            /// Which versions read this key.
            pub const fn since(self) -> Since {
                match self { $( Key::$key => Since::$since, )* }
            }
            /// One-line description with units.
            pub const fn doc(self) -> &'static str {
                match self { $( Key::$key => $doc, )* }
            }
            /// Looks a key up by name, ignoring ASCII case.
            pub fn from_name(name: &str) -> Option<Key> {
                Key::ALL.iter().copied().find(|k| k.name().eq_ignore_ascii_case(name))
            }
        }

        /// A Magic Formula parameter set. Field names are the `.tir` keys in lower case.
        ///
        /// Build one with [`crate::tir::parse`] (host or device: no allocation), or as a `const`
        /// for a device that has no file system. `F` is `f32` on the device, `f64` on the host;
        /// [`Params::cast`] converts. Units SI, axes ISO-W.
        #[derive(Debug, Clone, PartialEq)]
        pub struct Params<F> {
            /// Version of the equations (`FITTYP`).
            pub version: Version,
            /// Side the tyre was measured on (`TYRESIDE`); `None` when the file says
            /// `'UNKNOWN'` or nothing (then no mirroring is ever applied).
            pub tyreside: Option<Side>,
            $( #[doc = $doc] pub $field: F, )*
        }

        impl<F: Real> Params<F> {
            /// All numeric fields zero, λ's one; version as given. A starting point for
            /// building a parameter set in code; not a usable tyre by itself.
            pub fn zeroed(version: Version) -> Self {
                let mut p = Params { version, tyreside: None, $( $field: F::ZERO, )* };
                for &k in Key::ALL {
                    if k.need() == Need::Scale {
                        p.set(k, F::ONE);
                    }
                }
                p
            }
            /// Reads a parameter by key.
            pub fn get(&self, key: Key) -> F {
                match key { $( Key::$key => self.$field, )* }
            }
            /// Writes a parameter by key.
            pub fn set(&mut self, key: Key, value: F) {
                match key { $( Key::$key => self.$field = value, )* }
            }
            /// Whether a tyre mounted on `mounted` is the mirror image of this file's tyre (the
            /// side differs from `TYRESIDE`; never when either is unknown).
            pub fn mirrored_on(&self, mounted: Option<Side>) -> bool {
                matches!((mounted, self.tyreside), (Some(m), Some(s)) if m != s)
            }
        }

        impl<F: Float> Params<F> {
            /// The same parameter set in another float type (f64 → f32 rounds to nearest), or
            /// in lanes ([`crate::math::Lanes`]: every lane the parameter).
            pub fn cast<G: Real>(&self) -> Params<G> {
                Params {
                    version: self.version,
                    tyreside: self.tyreside,
                    $( $field: G::from_f64(self.$field.to_f64()), )*
                }
            }
        }
    };
}

tir_params! {
    // [MODEL] / [DIMENSION] / [OPERATING_CONDITIONS] / [VERTICAL]
    LONGVL longvl Required All "Nominal (reference) speed V0 \\[m/s\\].";
    VXLOW vxlow Required All "Speed below which the low-speed reductions act \\[m/s\\].";
    UNLOADED_RADIUS unloaded_radius Required All "Free tyre radius R0 \\[m\\].";
    WIDTH width Extension All "Nominal section width \\[m\\].";
    RIM_RADIUS rim_radius Extension All "Nominal rim radius \\[m\\].";
    INFLPRES inflpres Required Mf6 "Inflation pressure used when the input gives none \\[Pa\\].";
    NOMPRES nompres Required Mf6 "Nominal inflation pressure pi0 \\[Pa\\].";
    FNOMIN fnomin Required All "Nominal (rated) load Fz0 \\[N\\].";
    VERTICAL_STIFFNESS vertical_stiffness Required Mf6 "Vertical stiffness Cz0 \\[N/m\\].";
    PFZ1 pfz1 Extension Mf6 "Pressure effect on vertical stiffness \\[-\\].";
    BREFF breff Extension Mf6 "Low-load stiffness of the effective rolling radius \\[-\\].";
    DREFF dreff Extension Mf6 "Peak value of the effective rolling radius \\[-\\].";
    FREFF freff Extension Mf6 "High-load stiffness of the effective rolling radius \\[-\\].";
    Q_RE0 q_re0 Extension Mf6 "Ratio of free tyre radius to nominal radius \\[-\\].";
    Q_V1 q_v1 Extension Mf6 "Tyre radius increase with speed \\[-\\].";
    // [STRUCTURAL]
    LONGITUDINAL_STIFFNESS longitudinal_stiffness Extension Mf6 "Longitudinal carcass stiffness Cx0 \\[N/m\\].";
    LATERAL_STIFFNESS lateral_stiffness Extension Mf6 "Lateral carcass stiffness Cy0 \\[N/m\\].";
    PCFX1 pcfx1 Extension Mf6 "Cx: load dependency, linear \\[-\\].";
    PCFX2 pcfx2 Extension Mf6 "Cx: load dependency, quadratic \\[-\\].";
    PCFX3 pcfx3 Extension Mf6 "Cx: pressure dependency \\[-\\].";
    PCFY1 pcfy1 Extension Mf6 "Cy: load dependency, linear \\[-\\].";
    PCFY2 pcfy2 Extension Mf6 "Cy: load dependency, quadratic \\[-\\].";
    PCFY3 pcfy3 Extension Mf6 "Cy: pressure dependency \\[-\\].";
    DAMP_VLOW damp_vlow Extension Mf6 "Additional low-speed damping, proportional to stiffness \\[s\\] (used by `relax`).";
    // ranges
    PRESMIN presmin Range Mf6 "Minimum valid inflation pressure \\[Pa\\].";
    PRESMAX presmax Range Mf6 "Maximum valid inflation pressure \\[Pa\\].";
    FZMIN fzmin Range All "Minimum valid load \\[N\\].";
    FZMAX fzmax Range All "Maximum valid load \\[N\\].";
    KPUMIN kpumin Range All "Minimum valid longitudinal slip \\[-\\].";
    KPUMAX kpumax Range All "Maximum valid longitudinal slip \\[-\\].";
    ALPMIN alpmin Range All "Minimum valid slip angle \\[rad\\].";
    ALPMAX alpmax Range All "Maximum valid slip angle \\[rad\\].";
    CAMMIN cammin Range All "Minimum valid inclination angle \\[rad\\].";
    CAMMAX cammax Range All "Maximum valid inclination angle \\[rad\\].";
    // [SCALING_COEFFICIENTS]
    LFZO lfzo Scale All "λFz0: nominal (rated) load.";
    LCX lcx Scale All "λCx: Fx shape factor.";
    LMUX lmux Scale All "λμx: Fx peak friction coefficient.";
    LEX lex Scale All "λEx: Fx curvature factor.";
    LKX lkx Scale All "λKx: Fx slip stiffness.";
    LHX lhx Scale All "λHx: Fx horizontal shift.";
    LVX lvx Scale All "λVx: Fx vertical shift.";
    LGAX lgax Scale Mf5Only "λγx: camber for Fx (MF 5.x).";
    LCY lcy Scale All "λCy: Fy shape factor.";
    LMUY lmuy Scale All "λμy: Fy peak friction coefficient.";
    LEY ley Scale All "λEy: Fy curvature factor.";
    LKY lky Scale All "λKy: cornering stiffness.";
    LKYC lkyc Scale Mf6 "λKyγ: camber force stiffness (MF 6.x).";
    LKZC lkzc Scale Mf6 "λKzγ: camber torque stiffness (MF 6.x).";
    LHY lhy Scale All "λHy: Fy horizontal shift.";
    LVY lvy Scale All "λVy: Fy vertical shift.";
    LGAY lgay Scale Mf5Only "λγy: camber for Fy (Delft 96, MF 5.x).";
    LTR ltr Scale All "λt: peak of pneumatic trail.";
    LRES lres Scale All "λMr: offset of residual torque.";
    LGAZ lgaz Scale Mf5Only "λγz: camber for Mz (Delft 96, MF 5.x).";
    LXAL lxal Scale All "λxα: α influence on Fx(κ).";
    LYKA lyka Scale All "λyκ: κ influence on Fy(α).";
    LVYKA lvyka Scale All "λVyκ: κ-induced 'ply-steer' Fy.";
    LS ls Scale All "λs: Mz moment arm of Fx.";
    LSGKP lsgkp Scale Mf5Only "λσκ: longitudinal relaxation length (MF 5.x).";
    LSGAL lsgal Scale Mf5Only "λσα: lateral relaxation length (MF 5.x).";
    LMX lmx Scale All "λMx: overturning couple.";
    LVMX lvmx Scale Mf52 "λVMx: Mx vertical shift.";
    LMY lmy Scale All "λMy: rolling resistance torque.";
    LMP lmp Scale Mf6 "λMφ: parking torque (turn slip).";
    // [LONGITUDINAL_COEFFICIENTS]
    PCX1 pcx1 Required All "Shape factor Cfx (> 0) \\[-\\].";
    PDX1 pdx1 Required All "Longitudinal friction μx at Fz0 \\[-\\].";
    PDX2 pdx2 Required All "Variation of μx with load \\[-\\].";
    PDX3 pdx3 Extension Mf52 "Variation of μx with camber squared \\[-\\].";
    PEX1 pex1 Required All "Curvature Efx at Fz0 \\[-\\].";
    PEX2 pex2 Required All "Variation of Efx with load \\[-\\].";
    PEX3 pex3 Required All "Variation of Efx with load squared \\[-\\].";
    PEX4 pex4 Required All "Factor in Efx while driving \\[-\\].";
    PKX1 pkx1 Required All "Slip stiffness Kfx/Fz at Fz0 \\[-\\].";
    PKX2 pkx2 Required All "Variation of Kfx/Fz with load \\[-\\].";
    PKX3 pkx3 Required All "Exponent in Kfx/Fz with load \\[-\\].";
    PHX1 phx1 Required All "Horizontal shift Shx at Fz0 \\[-\\].";
    PHX2 phx2 Required All "Variation of Shx with load \\[-\\].";
    PVX1 pvx1 Required All "Vertical shift Svx/Fz at Fz0 \\[-\\].";
    PVX2 pvx2 Required All "Variation of Svx/Fz with load \\[-\\].";
    PPX1 ppx1 Required Mf6 "Linear pressure influence on Kxk \\[-\\].";
    PPX2 ppx2 Required Mf6 "Quadratic pressure influence on Kxk \\[-\\].";
    PPX3 ppx3 Required Mf6 "Linear pressure influence on μx \\[-\\].";
    PPX4 ppx4 Required Mf6 "Quadratic pressure influence on μx \\[-\\].";
    RBX1 rbx1 Extension All "Slope factor of combined-slip Fx reduction \\[-\\].";
    RBX2 rbx2 Extension All "Variation of that slope with κ \\[-\\].";
    RBX3 rbx3 Extension Mf6 "Influence of camber on that slope \\[-\\].";
    RCX1 rcx1 Extension All "Shape factor of combined-slip Fx reduction \\[-\\].";
    REX1 rex1 Extension Mf52 "Curvature of combined Fx \\[-\\].";
    REX2 rex2 Extension Mf52 "Curvature of combined Fx with load \\[-\\].";
    RHX1 rhx1 Extension All "Shift of combined-slip Fx reduction \\[-\\].";
    PTX1 ptx1 Extension Mf5Only "Relaxation length σκ0/Fz at Fz0 (MF 5.x) \\[m/N·Fz0/R0\\].";
    PTX2 ptx2 Extension Mf5Only "Variation of σκ0/Fz with load \\[-\\].";
    PTX3 ptx3 Extension Mf5Only "Variation of σκ0/Fz with exponent of load \\[-\\].";
    // [OVERTURNING_COEFFICIENTS]
    QSX1 qsx1 Extension All "Vertical shift of overturning moment \\[-\\].";
    QSX2 qsx2 Extension All "Camber-induced overturning couple \\[-\\].";
    QSX3 qsx3 Extension All "Fy-induced overturning couple \\[-\\].";
    QSX4 qsx4 Extension Mf6 "Mixed load, lateral force and camber on Mx \\[-\\].";
    QSX5 qsx5 Extension Mf6 "Load effect on Mx with lateral force and camber \\[-\\].";
    QSX6 qsx6 Extension Mf6 "B-factor of load with Mx \\[-\\].";
    QSX7 qsx7 Extension Mf6 "Camber with load on Mx \\[-\\].";
    QSX8 qsx8 Extension Mf6 "Lateral force with load on Mx \\[-\\].";
    QSX9 qsx9 Extension Mf6 "B-factor of lateral force with load on Mx \\[-\\].";
    QSX10 qsx10 Extension Mf6 "Vertical force with camber on Mx \\[-\\].";
    QSX11 qsx11 Extension Mf6 "B-factor of vertical force with camber on Mx \\[-\\].";
    QSX12 qsx12 Extension Mf6 "Camber-squared-induced overturning moment \\[-\\].";
    QSX13 qsx13 Extension Mf6 "Lateral-force-induced overturning moment \\[-\\].";
    QSX14 qsx14 Extension Mf6 "Lateral-force-induced overturning moment with camber \\[-\\].";
    PPMX1 ppmx1 Extension Mf6 "Pressure influence on overturning moment \\[-\\].";
    // [LATERAL_COEFFICIENTS]
    PCY1 pcy1 Required All "Shape factor Cfy (> 0) \\[-\\].";
    PDY1 pdy1 Required All "Lateral friction μy at Fz0 \\[-\\].";
    PDY2 pdy2 Required All "Variation of μy with load \\[-\\].";
    PDY3 pdy3 Required All "Variation of μy with camber squared \\[-\\].";
    PEY1 pey1 Required All "Curvature Efy at Fz0 \\[-\\].";
    PEY2 pey2 Required All "Variation of Efy with load \\[-\\].";
    PEY3 pey3 Required All "Zero-order camber dependency of Efy \\[-\\].";
    PEY4 pey4 Required All "Variation of Efy with camber \\[-\\].";
    PEY5 pey5 Required Mf6 "Variation of Efy with camber squared \\[-\\].";
    PKY1 pky1 Required All "Maximum of cornering stiffness Kfy/Fz0 \\[-\\].";
    PKY2 pky2 Required All "Load at which Kfy peaks, /Fz0 \\[-\\].";
    PKY3 pky3 Required All "Variation of Kfy/Fz0 with camber \\[-\\].";
    PKY4 pky4 Required Mf6 "Curvature of Kfy (MF 5.x: the constant 2) \\[-\\].";
    PKY5 pky5 Required Mf6 "Peak-stiffness variation with camber squared \\[-\\].";
    PKY6 pky6 Required Mf6 "Fy camber stiffness factor \\[-\\].";
    PKY7 pky7 Required Mf6 "Load dependency of camber stiffness \\[-\\].";
    PHY1 phy1 Required All "Horizontal shift Shy at Fz0 \\[-\\].";
    PHY2 phy2 Required All "Variation of Shy with load \\[-\\].";
    PHY3 phy3 Required Mf5Only "Variation of Shy with camber (MF 5.x) \\[-\\].";
    PVY1 pvy1 Required All "Vertical shift Svy/Fz at Fz0 \\[-\\].";
    PVY2 pvy2 Required All "Variation of Svy/Fz with load \\[-\\].";
    PVY3 pvy3 Required All "Variation of Svy/Fz with camber \\[-\\].";
    PVY4 pvy4 Required All "Variation of Svy/Fz with camber and load \\[-\\].";
    PPY1 ppy1 Required Mf6 "Pressure influence on cornering stiffness \\[-\\].";
    PPY2 ppy2 Required Mf6 "Pressure influence on the load of peak cornering stiffness \\[-\\].";
    PPY3 ppy3 Required Mf6 "Linear pressure influence on μy \\[-\\].";
    PPY4 ppy4 Required Mf6 "Quadratic pressure influence on μy \\[-\\].";
    PPY5 ppy5 Required Mf6 "Pressure influence on camber stiffness \\[-\\].";
    RBY1 rby1 Extension All "Slope factor of combined Fy reduction \\[-\\].";
    RBY2 rby2 Extension All "Variation of that slope with α \\[-\\].";
    RBY3 rby3 Extension All "Shift of α in that slope \\[-\\].";
    RBY4 rby4 Extension Mf6 "Influence of camber on that slope \\[-\\].";
    RCY1 rcy1 Extension All "Shape factor of combined Fy reduction \\[-\\].";
    REY1 rey1 Extension Mf52 "Curvature of combined Fy \\[-\\].";
    REY2 rey2 Extension Mf52 "Curvature of combined Fy with load \\[-\\].";
    RHY1 rhy1 Extension All "Shift of combined Fy reduction \\[-\\].";
    RHY2 rhy2 Extension Mf52 "Shift of combined Fy reduction with load \\[-\\].";
    RVY1 rvy1 Extension All "κ-induced side force Svyk/(μy·Fz) at Fz0 \\[-\\].";
    RVY2 rvy2 Extension All "Variation of Svyk/(μy·Fz) with load \\[-\\].";
    RVY3 rvy3 Extension All "Variation of Svyk/(μy·Fz) with camber \\[-\\].";
    RVY4 rvy4 Extension All "Variation of Svyk/(μy·Fz) with α \\[-\\].";
    RVY5 rvy5 Extension All "Variation of Svyk/(μy·Fz) with κ \\[-\\].";
    RVY6 rvy6 Extension All "Variation of Svyk/(μy·Fz) with atan(κ) \\[-\\].";
    PTY1 pty1 Extension Mf5Only "Peak of relaxation length σα0/R0 (MF 5.x) \\[-\\].";
    PTY2 pty2 Extension Mf5Only "Value of Fz/Fz0 where σα0 peaks (MF 5.x) \\[-\\].";
    // [ROLLING_COEFFICIENTS]
    QSY1 qsy1 Extension All "Rolling resistance torque coefficient \\[-\\].";
    QSY2 qsy2 Extension All "Rolling resistance depending on Fx \\[-\\].";
    QSY3 qsy3 Extension Mf52 "Rolling resistance depending on speed \\[-\\].";
    QSY4 qsy4 Extension Mf52 "Rolling resistance depending on speed^4 \\[-\\].";
    QSY5 qsy5 Extension Mf6 "Rolling resistance depending on camber squared \\[-\\].";
    QSY6 qsy6 Extension Mf6 "Rolling resistance depending on load and camber squared \\[-\\].";
    QSY7 qsy7 Extension Mf6 "Rolling resistance load exponent \\[-\\].";
    QSY8 qsy8 Extension Mf6 "Rolling resistance pressure exponent \\[-\\].";
    // [ALIGNING_COEFFICIENTS]
    QBZ1 qbz1 Required All "Trail slope factor Bpt at Fz0 \\[-\\].";
    QBZ2 qbz2 Required All "Variation of Bpt with load \\[-\\].";
    QBZ3 qbz3 Required All "Variation of Bpt with load squared \\[-\\].";
    QBZ4 qbz4 Required All "Variation of Bpt with camber \\[-\\].";
    QBZ5 qbz5 Required All "Variation of Bpt with |camber| \\[-\\].";
    QBZ9 qbz9 Required All "Factor for the scaling of Br of Mzr \\[-\\].";
    QBZ10 qbz10 Extension Mf52 "Factor of dimensionless cornering stiffness in Br of Mzr \\[-\\].";
    QCZ1 qcz1 Required All "Shape factor Cpt of pneumatic trail (> 0) \\[-\\].";
    QDZ1 qdz1 Required All "Peak trail Dpt/(Fz·R0/Fz0) \\[-\\].";
    QDZ2 qdz2 Required All "Variation of peak trail with load \\[-\\].";
    QDZ3 qdz3 Required All "Variation of peak trail with camber \\[-\\].";
    QDZ4 qdz4 Required All "Variation of peak trail with camber squared \\[-\\].";
    QDZ6 qdz6 Required All "Peak residual torque Dmr/(Fz·R0) \\[-\\].";
    QDZ7 qdz7 Required All "Variation of Dmr with load \\[-\\].";
    QDZ8 qdz8 Required All "Variation of Dmr with camber \\[-\\].";
    QDZ9 qdz9 Required All "Variation of Dmr with camber and load \\[-\\].";
    QDZ10 qdz10 Extension Mf6 "Variation of Dmr with camber squared \\[-\\].";
    QDZ11 qdz11 Extension Mf6 "Variation of Dmr with camber squared and load \\[-\\].";
    QEZ1 qez1 Required All "Trail curvature Ept at Fz0 \\[-\\].";
    QEZ2 qez2 Required All "Variation of Ept with load \\[-\\].";
    QEZ3 qez3 Required All "Variation of Ept with load squared \\[-\\].";
    QEZ4 qez4 Required All "Variation of Ept with sign of αt \\[-\\].";
    QEZ5 qez5 Required All "Variation of Ept with camber and sign of αt \\[-\\].";
    QHZ1 qhz1 Required All "Trail horizontal shift Sht at Fz0 \\[-\\].";
    QHZ2 qhz2 Required All "Variation of Sht with load \\[-\\].";
    QHZ3 qhz3 Required All "Variation of Sht with camber \\[-\\].";
    QHZ4 qhz4 Required All "Variation of Sht with camber and load \\[-\\].";
    PPZ1 ppz1 Required Mf6 "Pressure effect on the length of pneumatic trail \\[-\\].";
    PPZ2 ppz2 Required Mf6 "Pressure influence on residual aligning torque \\[-\\].";
    SSZ1 ssz1 Extension All "Nominal s/R0: effect of Fx on Mz \\[-\\].";
    SSZ2 ssz2 Extension All "Variation of s/R0 with Fy/Fz0 \\[-\\].";
    SSZ3 ssz3 Extension All "Variation of s/R0 with camber \\[-\\].";
    SSZ4 ssz4 Extension All "Variation of s/R0 with load and camber \\[-\\].";
    // [TURNSLIP_COEFFICIENTS]
    PDXP1 pdxp1 TurnSlip Mf6 "Peak Fx reduction due to spin \\[-\\].";
    PDXP2 pdxp2 TurnSlip Mf6 "Peak Fx reduction due to spin with load \\[-\\].";
    PDXP3 pdxp3 TurnSlip Mf6 "Peak Fx reduction due to spin with κ \\[-\\].";
    PKYP1 pkyp1 TurnSlip Mf6 "Cornering stiffness reduction due to spin \\[-\\].";
    PDYP1 pdyp1 TurnSlip Mf6 "Peak Fy reduction due to spin \\[-\\].";
    PDYP2 pdyp2 TurnSlip Mf6 "Peak Fy reduction due to spin with load \\[-\\].";
    PDYP3 pdyp3 TurnSlip Mf6 "Peak Fy reduction due to spin with α \\[-\\].";
    PDYP4 pdyp4 TurnSlip Mf6 "Peak Fy reduction due to √spin \\[-\\].";
    PHYP1 phyp1 TurnSlip Mf6 "Fy-α curve lateral shift limitation \\[-\\].";
    PHYP2 phyp2 TurnSlip Mf6 "Fy-α curve maximum lateral shift \\[-\\].";
    PHYP3 phyp3 TurnSlip Mf6 "Fy-α curve maximum lateral shift with load \\[-\\].";
    PHYP4 phyp4 TurnSlip Mf6 "Fy-α curve lateral shift curvature \\[-\\].";
    PECP1 pecp1 TurnSlip Mf6 "Camber reduction factor εγ at Fz0 \\[-\\].";
    PECP2 pecp2 TurnSlip Mf6 "Variation of εγ with load \\[-\\].";
    QDTP1 qdtp1 TurnSlip Mf6 "Pneumatic trail reduction due to turn slip \\[-\\].";
    QCRP1 qcrp1 TurnSlip Mf6 "Turning moment at constant turning and zero speed \\[-\\].";
    QCRP2 qcrp2 TurnSlip Mf6 "Turn-slip moment (at α = 90°) increase \\[-\\].";
    QBRP1 qbrp1 TurnSlip Mf6 "Residual (spin) torque reduction due to side slip \\[-\\].";
    QDRP1 qdrp1 TurnSlip Mf6 "Turn-slip moment peak magnitude \\[-\\].";
}

/// `.tir` keys that are recognised and deliberately not used (file metadata, dynamic-model and
/// geometry parameters outside the steady-state force model). They produce no warning.
pub const IGNORED_KEYS: &[&str] = &[
    "FILE_TYPE",
    "FILE_VERSION",
    "FILE_FORMAT",
    "LENGTH",
    "FORCE",
    "ANGLE",
    "MASS",
    "TIME",
    "FITTYP",
    "TYRESIDE",
    "PROPERTY_FILE_FORMAT",
    "USER_SUB_ID",
    "N_TIRE_STATES",
    "USE_MODE",
    "HMAX_LOCAL",
    "TIME_SWITCH_INTEG",
    "ROAD_INCREMENT",
    "ROAD_DIRECTION",
    "ASPECT_RATIO",
    "RIM_WIDTH",
    "IXX",
    "IYY",
    "BELT_MASS",
    "BELT_IXX",
    "BELT_IYY",
    "GRAVITY",
    "VERTICAL_DAMPING",
    "MC_CONTOUR_A",
    "MC_CONTOUR_B",
    "BOTTOM_OFFST",
    "BOTTOM_STIFF",
    "Q_V2",
    "Q_FZ2",
    "Q_FCX",
    "Q_FCY",
    "Q_FCY2",
    "Q_CAM",
    "Q_CAM1",
    "Q_CAM2",
    "Q_CAM3",
    "Q_FYS1",
    "Q_FYS2",
    "Q_FYS3",
    "Q_FZ3",
    "Q_RA1",
    "Q_RA2",
    "Q_RB1",
    "Q_RB2",
    "ELLIPS_SHIFT",
    "ELLIPS_LENGTH",
    "ELLIPS_HEIGHT",
    "ELLIPS_ORDER",
    "ELLIPS_MAX_STEP",
    "ELLIPS_NWIDTH",
    "ELLIPS_NLENGTH",
    "YAW_STIFFNESS",
    "FREQ_LONG",
    "FREQ_LAT",
    "FREQ_YAW",
    "FREQ_WINDUP",
    "DAMP_LONG",
    "DAMP_LAT",
    "DAMP_YAW",
    "DAMP_WINDUP",
    "DAMP_RESIDUAL",
    "Q_BVX",
    "Q_BVT",
    "PCMZ1",
    "QTZ1",
    "MBELT",
    "LGYR",
    "LCZ",
    "LKG",
    "LIP",
    "LMUV",
    "PTX4",
    "PTY3",
    "QPX1",
    "QPZ1",
    "QPZ2",
    "QDRP2",
    "BOTTOMING_RADIUS",
    "BELT_DYNAMICS",
    "CONTACT_MODEL",
    "DYNAMIC_DAMPING",
    "DYNAMIC_STIFFNESS",
    "ENV_C1",
    "ENV_C2",
    "FE_METHOD",
    "LOCAL_SOLVER",
    "LOCAL_SOLVER_HP",
    "MESSAGES",
    "MFSAFE1",
    "MFSAFE2",
    "MFSAFE3",
    "CONSTRUCTION",
    "DATESTAMP",
    "TEST_DEVICE",
    "TEST_NUMBER",
    "TIRE_DASH",
    "TIRE_DOT",
    "TYPE_TEST_NUMBER",
    "PRESSURE",
    "INFLATION_PRESSURE",
];

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn key_names_round_trip() {
        for &k in Key::ALL {
            assert_eq!(Key::from_name(k.name()), Some(k));
            assert_eq!(Key::from_name(&k.name().to_ascii_lowercase()), Some(k));
            assert!(
                !IGNORED_KEYS.contains(&k.name()),
                "{} both used and ignored",
                k.name()
            );
        }
    }

    #[test]
    fn get_set_cast() {
        let mut p = Params::<f64>::zeroed(Version::Mf61);
        assert_eq!(p.lmuy, 1.0);
        assert_eq!(p.pcx1, 0.0);
        p.set(Key::PCX1, 1.65);
        assert_eq!(p.get(Key::PCX1), 1.65);
        let q: Params<f32> = p.cast();
        assert_eq!(q.pcx1, 1.65f32);
        assert_eq!(q.version, Version::Mf61);
    }
}
