//! The parametric body: MakeHuman hm08 macro parameters and local
//! modifiers → a skin mesh in metres.
//!
//! `body = base + Σ_i w_i · target_i` with the weights of MakeHuman's macro
//! model (`../shared/makehuman/README.md`): every macro parameter is in
//! [0, 1], 0.5 neutral;
//! * gender g: female `1−g`, male `g`;
//! * age a ∈ [0.5, 1] (adults only): old `max(0, 2a−1)`, young `1 − old`;
//! * muscle m / weight w: `max = max(0, 2x−1)`, `min = max(0, 1−2x)`,
//!   `average = 1 − max − min`;
//! * height h: `maxheight = max(0, 2h−1)`, `minheight = max(0, 1−2h)`;
//! * proportions p: `ideal = max(0, 2p−1)`, `uncommon = max(0, 1−2p)`;
//! * race: african/asian/caucasian weights, normalised to sum 1.
//!
//! A universal target's weight is `G·A·M·W`, a height or proportions
//! target's `G·A·M·W·H` (resp. `·P`), a race target's `race·G·A`.
//! A local modifier `NAME ∈ [−1, 1]` applies `NAME-incr` with weight `v`
//! for `v > 0` and `NAME-decr` with weight `−v` for `v < 0` (pairs
//! `up/down`, `out/in`, `forward/backward` likewise).
//!
//! Failure modes: a parameter outside its range, a non-finite value, an
//! unknown modifier, race weights that sum to zero — each a
//! [`MannequinError`] naming the parameter.

use std::collections::BTreeMap;
use std::sync::OnceLock;

use glam::DVec3;
use serde::{Deserialize, Serialize};

use super::data::{self, DataError, Hm08Data, DELTA_UNIT_DM, POSITION_UNIT_DM};
use crate::geom::mesh::{MeshError, TriMesh, VertexId};

/// Metres per decimetre (MakeHuman's unit).
pub const METRES_PER_DM: f64 = 0.1;

static EMBEDDED: &[u8] = include_bytes!("../../../../templates/mannequin/hm08.bin.gz");

/// Macro parameters of the body model, each documented with its range.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct MacroParams {
    /// 0 female … 1 male. Default 0.5.
    pub gender: f64,
    /// 0.5 (25 years) … 1 (90 years). Default 0.5.
    pub age: f64,
    /// 0 … 1. Default 0.5.
    pub muscle: f64,
    /// 0 … 1. Default 0.5.
    pub weight: f64,
    /// 0 … 1. Default 0.5.
    pub height: f64,
    /// 0 (uncommon) … 1 (ideal). Default 0.5.
    pub proportions: f64,
    /// Race weight, ≥ 0; the three are normalised. Default 1/3.
    pub african: f64,
    /// Race weight, ≥ 0. Default 1/3.
    pub asian: f64,
    /// Race weight, ≥ 0. Default 1/3.
    pub caucasian: f64,
}

impl Default for MacroParams {
    fn default() -> Self {
        Self {
            gender: 0.5,
            age: 0.5,
            muscle: 0.5,
            weight: 0.5,
            height: 0.5,
            proportions: 0.5,
            african: 1.0 / 3.0,
            asian: 1.0 / 3.0,
            caucasian: 1.0 / 3.0,
        }
    }
}

/// Full description of a mannequin: macro parameters and local modifiers
/// (`"torso/measure-waist-circ": 0.3`, each in [−1, 1]).
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct MannequinParams {
    /// Macro parameters.
    #[serde(rename = "macro")]
    pub macros: MacroParams,
    /// Local modifiers by name.
    pub modifiers: BTreeMap<String, f64>,
}

/// What is wrong with mannequin parameters.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum MannequinError {
    /// A parameter is outside its range or not finite.
    #[error("parameter `{name}` = {value} is outside [{min}, {max}]")]
    OutOfRange {
        /// Parameter name.
        name: String,
        /// Given value.
        value: f64,
        /// Lower bound.
        min: f64,
        /// Upper bound.
        max: f64,
    },
    /// No target pair exists for this modifier.
    #[error("unknown modifier `{name}`")]
    UnknownModifier {
        /// The name given.
        name: String,
    },
    /// All race weights are zero.
    #[error("the race weights african/asian/caucasian sum to zero")]
    RaceWeights,
    /// The embedded data is corrupt (an internal error).
    #[error("embedded body model: {0}")]
    Data(String),
    /// The resulting mesh is invalid (an internal error).
    #[error("body mesh: {0}")]
    Mesh(#[from] MeshError),
}

impl From<DataError> for MannequinError {
    fn from(e: DataError) -> Self {
        MannequinError::Data(e.to_string())
    }
}

/// The hm08 model in floating point, ready to evaluate.
#[derive(Debug)]
pub struct BodyModel {
    data: Hm08Data,
    triangles: Vec<[VertexId; 3]>,
}

const MODIFIER_PAIRS: &[(&str, &str)] = &[("incr", "decr"), ("up", "down"), ("out", "in"), ("forward", "backward")];

fn check(name: &str, value: f64, min: f64, max: f64) -> Result<f64, MannequinError> {
    if value.is_finite() && value >= min && value <= max {
        Ok(value)
    } else {
        Err(MannequinError::OutOfRange { name: name.to_owned(), value, min, max })
    }
}

/// `(min, average, max)` weights of a three-level macro parameter.
fn three_level(x: f64) -> [f64; 3] {
    let max = (2.0 * x - 1.0).max(0.0);
    let min = (1.0 - 2.0 * x).max(0.0);
    [min, 1.0 - max - min, max]
}

impl BodyModel {
    /// The embedded model, decoded once per process.
    pub fn embedded() -> Result<&'static BodyModel, MannequinError> {
        static MODEL: OnceLock<Result<BodyModel, MannequinError>> = OnceLock::new();
        MODEL.get_or_init(|| Self::from_data(data::decode(EMBEDDED)?)).as_ref().map_err(Clone::clone)
    }

    /// A model from decoded data.
    pub fn from_data(data: Hm08Data) -> Result<Self, MannequinError> {
        let triangles = data.triangles.iter().map(|t| t.map(|v| VertexId(u32::from(v)))).collect();
        Ok(Self { data, triangles })
    }

    /// The raw data (rings, mirror map).
    pub fn data(&self) -> &Hm08Data {
        &self.data
    }

    /// Mirror vertex of `v` across the sagittal plane.
    pub fn mirror(&self, v: VertexId) -> VertexId {
        VertexId(u32::from(self.data.mirror.get(v.idx()).copied().unwrap_or(v.0 as u16)))
    }

    /// Names of the local modifiers available (without `-incr`/`-decr`).
    pub fn modifier_names(&self) -> Vec<String> {
        let mut out: Vec<String> = self
            .data
            .targets
            .keys()
            .filter(|k| !k.starts_with("macrodetails"))
            .filter_map(|k| {
                MODIFIER_PAIRS.iter().find_map(|(p, _)| k.strip_suffix(&format!("-{p}")).map(str::to_owned))
            })
            .collect();
        out.sort();
        out.dedup();
        out
    }

    /// Target weights for the given parameters.
    pub fn target_weights(&self, params: &MannequinParams) -> Result<Vec<(&str, f64)>, MannequinError> {
        let m = &params.macros;
        let g = check("gender", m.gender, 0.0, 1.0)?;
        let a = check("age", m.age, 0.5, 1.0)?;
        let mu = check("muscle", m.muscle, 0.0, 1.0)?;
        let w = check("weight", m.weight, 0.0, 1.0)?;
        let h = check("height", m.height, 0.0, 1.0)?;
        let p = check("proportions", m.proportions, 0.0, 1.0)?;
        let races = [
            ("african", check("african", m.african, 0.0, 1.0)?),
            ("asian", check("asian", m.asian, 0.0, 1.0)?),
            ("caucasian", check("caucasian", m.caucasian, 0.0, 1.0)?),
        ];
        let race_sum: f64 = races.iter().map(|r| r.1).sum();
        if race_sum <= 0.0 {
            return Err(MannequinError::RaceWeights);
        }
        let genders = [("female", 1.0 - g), ("male", g)];
        let old = (2.0 * a - 1.0).max(0.0);
        let ages = [("young", 1.0 - old), ("old", old)];
        let [m0, m1, m2] = three_level(mu);
        let muscles = [("minmuscle", m0), ("averagemuscle", m1), ("maxmuscle", m2)];
        let [w0, w1, w2] = three_level(w);
        let weights = [("minweight", w0), ("averageweight", w1), ("maxweight", w2)];
        let heights = [("maxheight", (2.0 * h - 1.0).max(0.0)), ("minheight", (1.0 - 2.0 * h).max(0.0))];
        let props = [("idealproportions", (2.0 * p - 1.0).max(0.0)), ("uncommonproportions", (1.0 - 2.0 * p).max(0.0))];

        let mut out: Vec<(&str, f64)> = Vec::new();
        let mut push = |name: String, weight: f64| {
            if weight > 0.0 {
                if let Some((k, _)) = self.data.targets.get_key_value(&name) {
                    out.push((k.as_str(), weight));
                }
            }
        };
        for (gn, gw) in genders {
            for (an, aw) in ages {
                for (rn, rw) in races {
                    push(format!("macrodetails/{rn}-{gn}-{an}"), rw / race_sum * gw * aw);
                }
                for (mn, mw) in muscles {
                    for (wn, ww) in weights {
                        let base = gw * aw * mw * ww;
                        push(format!("macrodetails/universal-{gn}-{an}-{mn}-{wn}"), base);
                        for (hn, hw) in heights {
                            push(format!("macrodetails/height/{gn}-{an}-{mn}-{wn}-{hn}"), base * hw);
                        }
                        for (pn, pw) in props {
                            push(format!("macrodetails/proportions/{gn}-{an}-{mn}-{wn}-{pn}"), base * pw);
                        }
                    }
                }
            }
        }
        for (name, &v) in &params.modifiers {
            let v = check(name, v, -1.0, 1.0)?;
            let pair = MODIFIER_PAIRS.iter().find(|(p, n)| {
                self.data.targets.contains_key(&format!("{name}-{p}"))
                    || self.data.targets.contains_key(&format!("{name}-{n}"))
            });
            let Some((pos, neg)) = pair else {
                return Err(MannequinError::UnknownModifier { name: name.clone() });
            };
            if v > 0.0 {
                push(format!("{name}-{pos}"), v);
            } else if v < 0.0 {
                push(format!("{name}-{neg}"), -v);
            }
        }
        Ok(out)
    }

    /// Vertex positions in metres for the given parameters.
    pub fn positions(&self, params: &MannequinParams) -> Result<Vec<DVec3>, MannequinError> {
        let weights = self.target_weights(params)?;
        let mut pos: Vec<DVec3> = self
            .data
            .positions
            .iter()
            .map(|p| DVec3::new(f64::from(p[0]), f64::from(p[1]), f64::from(p[2])) * POSITION_UNIT_DM)
            .collect();
        for (name, w) in weights {
            let s = w * DELTA_UNIT_DM;
            for (v, d) in &self.data.targets[name] {
                pos[*v as usize] += DVec3::new(f64::from(d[0]), f64::from(d[1]), f64::from(d[2])) * s;
            }
        }
        for p in &mut pos {
            *p *= METRES_PER_DM;
        }
        Ok(pos)
    }

    /// The model's base mesh in metres, no target applied: the body
    /// MakeHuman's own helper geometry (`helper-skirt`, `helper-tights`,
    /// `fixtures/garments/`) was modelled on, hence the design body of the
    /// garments made from it (issue #18's round trip).
    pub fn base_mesh(&self) -> Result<TriMesh, MannequinError> {
        let pos = self
            .data
            .positions
            .iter()
            .map(|p| DVec3::new(f64::from(p[0]), f64::from(p[1]), f64::from(p[2])) * POSITION_UNIT_DM * METRES_PER_DM)
            .collect();
        Ok(TriMesh::new(pos, self.triangles.clone())?)
    }

    /// The skin mesh in metres for the given parameters.
    pub fn build(&self, params: &MannequinParams) -> Result<TriMesh, MannequinError> {
        Ok(TriMesh::new(self.positions(params)?, self.triangles.clone())?)
    }

    /// The mesh triangles (shared by every body of this model).
    pub fn triangles(&self) -> &[[VertexId; 3]] {
        &self.triangles
    }
}
