//! Automatic landmarks (issue #17, item 2): the embedded hm08 body
//! registered to a scan, and every vocabulary landmark read off the
//! registered hm08 topology ([`hm08_landmarks`]) and put on the scan.
//!
//! # Method
//!
//! The scan is in the body frame ([`crate::body::frame`]: metres, `+Y` up,
//! facing `+Z`) and repaired ([`crate::geom::repair`]); the faces that
//! close its holes are not scanned skin and attract nothing.
//! 1. **Rigid start.** The model's soles on the scan's floor, the centres of
//!    their bounding boxes over each other; the `height` macro set by
//!    bisection so that the model's stature is the scan's.
//! 2. **Shape** (ICP over the model's parameters). A fixed subsample `S`
//!    of the model's vertices ([`RegisterOptions::samples`]); each round
//!    pairs every `p_i ∈ S` with its closest scan point `c_i` and drops the
//!    pairs farther than [`RegisterOptions::trim_factor`] × their median
//!    (at least [`RegisterOptions::min_trim_mm`]), whose normals differ by
//!    more than [`RegisterOptions::max_normal_angle_deg`], or whose scan
//!    point is on a hole's fill; then a few Levenberg–Marquardt steps on
//!
//!    `min_x (1/|P|) Σ_{i∈P} [(n_i·d_i)² + w² |d_i|²] + μ² |x − x₀|²`,
//!    `d_i = p_i(x) + t − c_i`,
//!
//!    point-to-plane along the scan's normal `n_i` (Chen & Medioni 1992:
//!    converges in a few rounds where point-to-point ICP crawls) with a
//!    small point-to-point term `w` = [`RegisterOptions::point_to_point_weight`]
//!    that keeps the model from sliding along flat skin,
//!    `x` the macro parameters (gender, age, muscle, weight, height,
//!    proportions, ethnic mix) and the girth modifiers of the size-chart
//!    fit ([`super::fit::modifier_for`]), each clamped to its range, `t`
//!    a translation, `μ` = [`RegisterOptions::prior_weight_mm`] per unit of
//!    parameter. The model is linear in its targets (`p = base + Σ w_k(x)
//!    Δ_k`), so `S`'s positions cost one pass over the targets' entries on
//!    `S`, and a Jacobian column `Σ_k ∂w_k/∂x_j Δ_k` only the targets whose
//!    weight `x_j` moves (the weights' forward difference; `t`'s columns are
//!    the identity).
//!    Gender is bimodal: a few rounds from each end, the better continued;
//!    where it settles in a local minimum (its samples farther than
//!    [`RegisterOptions::retry_above_mm`] from the scan), the other too,
//!    then the better gender from a start [`RegisterOptions::retry_stature_scale`]
//!    taller (a scan without its crown reads short), the best kept.
//! 3. **Non-rigid refinement** of the whole model surface: each round
//!    pairs every model vertex with its closest scan point as above
//!    (weight 1 if kept, 0 if not) and solves
//!
//!    `(W + λ L) D = W (C − P)`,
//!
//!    `L` the graph Laplacian of the hm08 mesh and `λ` =
//!    [`RegisterOptions::smoothness`] (a membrane on the displacements
//!    `D`: vertices over holes follow their neighbours), by faer's sparse
//!    Cholesky.
//! 4. **Landmarks**: [`hm08_landmarks`] on the registered surface, each
//!    moved to its closest point of the repaired scan (a crotch or armpit
//!    point may land on a hole's fill, which stands for the skin there;
//!    derivation snaps it to the surface as it does any landmark). Its
//!    *confidence* is
//!    `exp(−d / s)`, `d` the distance it moved and `s` =
//!    [`RegisterOptions::confidence_scale_mm`].
//! 5. **Residual**: the distance from scan points (face centroids, fills
//!    left out, at most [`RegisterOptions::residual_samples`]) to the
//!    registered surface, RMS and 95th percentile, mm. A registration
//!    whose residual exceeds [`RegisterOptions::max_rms_mm`] or
//!    [`RegisterOptions::max_p95_mm`] is refused ([`RegisterError::Residual`]):
//!    its landmarks would be guesses.
//!
//! # Failure modes
//!
//! [`RegisterError`]: the model's own errors, a landmark the registered
//! surface does not give, too few pairs to fit, or a residual over its bar.

use std::collections::BTreeMap;

use faer::linalg::solvers::Solve;
use faer::sparse::{SparseColMat, Triplet};
use faer::Side;
use glam::DVec3;
use rayon::prelude::*;
use rustc_hash::FxHashMap;
use serde::{Deserialize, Serialize};

use super::data::{DELTA_UNIT_DM, POSITION_UNIT_DM};
use super::fit::modifier_for;
use super::landmarks::{hm08_landmarks, Hm08LandmarkOptions, LandmarkError};
use super::model::{BodyModel, MannequinError, MannequinParams, METRES_PER_DM};
use crate::body::derive::{Landmarks, MM_PER_M};
use crate::body::measure::MeasurementId;
use crate::body::vocab::PointId;
use crate::geom::mesh::{FaceId, TriMesh};
use crate::geom::winding::{WindingOptions, WindingTree};

/// Knobs of [`register`].
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct RegisterOptions {
    /// Model vertices in the shape fit's subsample. Default 1500 (of
    /// 13,380: one in nine, every region of the body represented).
    pub samples: usize,
    /// ICP rounds of the shape fit from each gender start. Default 3.
    pub start_rounds: usize,
    /// ICP rounds after the better start. Default 8 (point-to-plane pairs
    /// converge in a few: on 20 scan-like population bodies the found
    /// landmarks' median and 95th-percentile errors are the same after 8
    /// rounds of 2 steps as after 12 of 3, 0.7 and 2–3 mm).
    pub rounds: usize,
    /// A shape fit whose samples lie farther from the scan than this (RMS,
    /// mm) is taken for a local minimum: the other gender start is
    /// continued too, and the better kept. Default 1.0 (the population's
    /// scan-like copies fit to 0.3–0.6 mm; 1.7–2.2 mm where a start went
    /// astray).
    pub retry_above_mm: f64,
    /// The last retry's start: the scan's height times this. Default 1.02
    /// (a scan whose crown or soles are missing reads 1–2 % short, and a
    /// shape fit started that short can settle short: the population body
    /// pop13 with a 4 cm hole at the crown fitted to 1.4 mm RMS instead of
    /// 0.5 mm).
    pub retry_stature_scale: f64,
    /// Levenberg–Marquardt steps per round. Default 2.
    pub lm_steps: usize,
    /// Forward-difference step, parameter units. Default 0.01.
    pub fd_step: f64,
    /// `μ`: the prior's weight, mm of RMS residual per unit of parameter.
    /// Default 0.5 (a parameter the scan does not constrain stays put;
    /// one it does moves for any gain over half a millimetre).
    pub prior_weight_mm: f64,
    /// Weight of the point-to-point residual beside the point-to-plane one
    /// (`n·d`, which converges in a few rounds but lets the model slide
    /// along flat skin). Default 0.2.
    pub point_to_point_weight: f64,
    /// Pairs farther than this many times the median are dropped.
    /// Default 3.
    pub trim_factor: f64,
    /// The trim distance is at least this, mm. Default 10.
    pub min_trim_mm: f64,
    /// Pairs whose normals differ by more than this are dropped, degrees.
    /// Default 60 (the inside of one thigh facing the other).
    pub max_normal_angle_deg: f64,
    /// Rounds of the non-rigid refinement. Default 2.
    pub refine_rounds: usize,
    /// `λ`, the membrane weight of the refinement per unit of data
    /// weight. Default 2 (displacements vary over a few edge lengths:
    /// noise of the scan is not copied onto the surface).
    pub smoothness: f64,
    /// Scan points the residual is measured on, at most. Default 4000.
    pub residual_samples: usize,
    /// Largest accepted RMS residual, mm. Default 6 (a registered scan
    /// of the issue #7 population measures 1–2 mm; clothing or a pose far
    /// from the A-pose measures 10 and more).
    pub max_rms_mm: f64,
    /// Largest accepted 95th-percentile residual, mm. Default 12.
    pub max_p95_mm: f64,
    /// Landmark confidence scale `s`, mm. Default 5.
    pub confidence_scale_mm: f64,
    /// The landmark finder on the registered surface.
    pub landmarks: Hm08LandmarkOptions,
}

impl Default for RegisterOptions {
    fn default() -> Self {
        Self {
            samples: 1500,
            start_rounds: 3,
            rounds: 8,
            lm_steps: 2,
            retry_above_mm: 1.0,
            retry_stature_scale: 1.02,
            fd_step: 0.01,
            prior_weight_mm: 0.5,
            point_to_point_weight: 0.2,
            trim_factor: 3.0,
            min_trim_mm: 10.0,
            max_normal_angle_deg: 60.0,
            refine_rounds: 2,
            smoothness: 2.0,
            residual_samples: 4000,
            max_rms_mm: 6.0,
            max_p95_mm: 12.0,
            confidence_scale_mm: 5.0,
            landmarks: Hm08LandmarkOptions::default(),
        }
    }
}

/// A scan registered, with its landmarks.
#[derive(Debug, Clone, PartialEq)]
pub struct Registration {
    /// The hm08 surface on the scan (the model's topology).
    pub surface: TriMesh,
    /// The model's parameters after the shape fit.
    pub params: MannequinParams,
    /// Every vocabulary landmark, on the scan.
    pub landmarks: Landmarks,
    /// The residual and the confidences.
    pub report: RegistrationReport,
}

/// What a registration reports.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, utoipa::ToSchema)]
pub struct RegistrationReport {
    /// RMS distance from the scan to the registered surface, mm.
    pub rms_mm: f64,
    /// Its 95th percentile, mm.
    pub p95_mm: f64,
    /// RMS distance from the model's sampled points to the scan after the
    /// shape fit alone (before the refinement), mm: how well the body
    /// model itself fits.
    pub shape_rms_mm: f64,
    /// Per landmark found (not supplied), `exp(−d / s)` with `d` how far it
    /// moved onto the scan (module docs).
    #[schema(value_type = BTreeMap<String, f64>)]
    pub confidence: BTreeMap<PointId, f64>,
}

/// Why a scan could not be registered.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum RegisterError {
    /// The model failed.
    #[error(transparent)]
    Model(#[from] MannequinError),
    /// The registered surface does not give a landmark.
    #[error(transparent)]
    Landmark(#[from] LandmarkError),
    /// Too few model points found scan skin near them.
    #[error("registration: only {pairs} of {samples} model points found the scan's surface near them")]
    TooFewPairs {
        /// Pairs kept.
        pairs: usize,
        /// Pairs tried.
        samples: usize,
    },
    /// The registered model does not fit the scan.
    #[error(
        "the body model does not fit the scan: scan-to-model distance RMS {rms_mm:.1} mm, 95th percentile \
         {p95_mm:.1} mm (allowed {max_rms_mm} and {max_p95_mm} mm); is it a body in close-fitting clothes, \
         in the A-pose? Give its landmarks instead"
    )]
    Residual {
        /// RMS, mm.
        rms_mm: f64,
        /// 95th percentile, mm.
        p95_mm: f64,
        /// Allowed RMS, mm.
        max_rms_mm: f64,
        /// Allowed 95th percentile, mm.
        max_p95_mm: f64,
    },
}

/// A parameter of the shape fit.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Var {
    Gender,
    Age,
    Muscle,
    Weight,
    Height,
    Proportions,
    African,
    Asian,
    Caucasian,
    Modifier(&'static str),
}

impl Var {
    fn range(self) -> [f64; 2] {
        match self {
            Var::Age => [super::population::ADULT_AGE, 1.0],
            Var::African | Var::Asian | Var::Caucasian => [0.01, 1.0],
            Var::Modifier(_) => [-1.0, 1.0],
            _ => [0.0, 1.0],
        }
    }

    fn get(self, p: &MannequinParams) -> f64 {
        let m = &p.macros;
        match self {
            Var::Gender => m.gender,
            Var::Age => m.age,
            Var::Muscle => m.muscle,
            Var::Weight => m.weight,
            Var::Height => m.height,
            Var::Proportions => m.proportions,
            Var::African => m.african,
            Var::Asian => m.asian,
            Var::Caucasian => m.caucasian,
            Var::Modifier(name) => p.modifiers.get(name).copied().unwrap_or(0.0),
        }
    }

    fn set(self, p: &mut MannequinParams, v: f64) {
        let [lo, hi] = self.range();
        let v = v.clamp(lo, hi);
        let m = &mut p.macros;
        match self {
            Var::Gender => m.gender = v,
            Var::Age => m.age = v,
            Var::Muscle => m.muscle = v,
            Var::Weight => m.weight = v,
            Var::Height => m.height = v,
            Var::Proportions => m.proportions = v,
            Var::African => m.african = v,
            Var::Asian => m.asian = v,
            Var::Caucasian => m.caucasian = v,
            Var::Modifier(name) => {
                p.modifiers.insert(name.to_owned(), v);
            }
        }
    }
}

/// The parameters of the shape fit: the macros and the girth modifiers.
fn variables() -> Vec<Var> {
    use MeasurementId as M;
    let mut vars = vec![
        Var::Gender,
        Var::Age,
        Var::Muscle,
        Var::Weight,
        Var::Height,
        Var::Proportions,
        Var::African,
        Var::Asian,
        Var::Caucasian,
    ];
    let mut names: Vec<&'static str> = [
        M::NeckBaseGirth,
        M::BustGirth,
        M::UnderbustGirth,
        M::WaistGirth,
        M::HipGirth,
        M::ShoulderWidth,
        M::ChestGirth,
        M::ThighGirth,
        M::KneeGirth,
        M::BackLength,
    ]
    .into_iter()
    .filter_map(modifier_for)
    .collect();
    names.sort_unstable();
    names.dedup();
    vars.extend(names.into_iter().map(Var::Modifier));
    vars
}

/// The model evaluated on a subsample of its vertices (module docs, step 2).
struct Sampled<'a> {
    model: &'a BodyModel,
    /// Model vertex of each sample.
    vertex: Vec<usize>,
    /// Base positions, m.
    base: Vec<DVec3>,
    /// Per target: (sample, delta in m per unit weight).
    targets: FxHashMap<&'a str, Vec<(u32, DVec3)>>,
}

impl<'a> Sampled<'a> {
    fn new(model: &'a BodyModel, count: usize) -> Self {
        let data = model.data();
        let n = data.positions.len();
        let stride = (n / count.max(1)).max(1);
        let mut vertex: Vec<usize> = (0..n).step_by(stride).collect();
        // the base mesh's extreme vertices (crown, soles, finger tips, nose, heels) give the
        // samples the body's bounding box
        for k in 0..3 {
            let key = |v: &usize| data.positions[*v][k];
            vertex.extend((0..n).min_by_key(key));
            vertex.extend((0..n).max_by_key(key));
        }
        vertex.sort_unstable();
        vertex.dedup();
        let mut slot = vec![u32::MAX; n];
        for (s, &v) in vertex.iter().enumerate() {
            slot[v] = s as u32;
        }
        let unit = |p: [i32; 3]| DVec3::new(f64::from(p[0]), f64::from(p[1]), f64::from(p[2]));
        let base = vertex.iter().map(|&v| unit(data.positions[v]) * POSITION_UNIT_DM * METRES_PER_DM).collect();
        let targets = data
            .targets
            .iter()
            .map(|(name, deltas)| {
                let on: Vec<(u32, DVec3)> = deltas
                    .iter()
                    .filter(|(v, _)| slot[usize::from(*v)] != u32::MAX)
                    .map(|(v, d)| {
                        let d = DVec3::new(f64::from(d[0]), f64::from(d[1]), f64::from(d[2]));
                        (slot[usize::from(*v)], d * DELTA_UNIT_DM * METRES_PER_DM)
                    })
                    .collect();
                (name.as_str(), on)
            })
            .collect();
        Self { model, vertex, base, targets }
    }

    /// `∂p/∂x` of every sample for one parameter, by a forward difference
    /// of the target weights alone: `Σ_k (w_k(x + h) − w_k(x)) / h · Δ_k`
    /// over the targets whose weight the step changes (the model is linear
    /// in its targets; a modifier moves one target, a macro a few dozen).
    fn column(&self, params: &MannequinParams, var: Var, step: f64) -> Result<Vec<DVec3>, MannequinError> {
        let x = var.get(params);
        let [lo, hi] = var.range();
        let h = if x + step <= hi { step } else { -step };
        let mut moved = params.clone();
        var.set(&mut moved, (x + h).clamp(lo, hi));
        let h = var.get(&moved) - x;
        let mut out = vec![DVec3::ZERO; self.base.len()];
        if h == 0.0 {
            return Ok(out);
        }
        let before: FxHashMap<&str, f64> = self.model.target_weights(params)?.into_iter().collect();
        let after: FxHashMap<&str, f64> = self.model.target_weights(&moved)?.into_iter().collect();
        let mut names: Vec<&str> = before.keys().chain(after.keys()).copied().collect();
        names.sort_unstable();
        names.dedup();
        for name in names {
            let dw = (after.get(name).copied().unwrap_or(0.0) - before.get(name).copied().unwrap_or(0.0)) / h;
            if dw == 0.0 {
                continue;
            }
            if let Some(deltas) = self.targets.get(name) {
                for &(s, d) in deltas {
                    out[s as usize] += d * dw;
                }
            }
        }
        Ok(out)
    }

    fn positions(&self, params: &MannequinParams) -> Result<Vec<DVec3>, MannequinError> {
        let mut out = self.base.clone();
        for (name, w) in self.model.target_weights(params)? {
            if let Some(deltas) = self.targets.get(name) {
                for &(s, d) in deltas {
                    out[s as usize] += d * w;
                }
            }
        }
        Ok(out)
    }
}

/// The scan as registration sees it: its closest-point tree and which
/// faces are skin (not a hole's fill).
struct Scan<'a> {
    mesh: &'a TriMesh,
    tree: WindingTree,
    skin: Vec<bool>,
}

impl Scan<'_> {
    /// The closest scan point to `p` and its face; `hint`, a scan point
    /// (the last answer for this model point), bounds the search.
    fn closest(&self, p: DVec3, hint: Option<DVec3>) -> (DVec3, FaceId, f64) {
        hint.and_then(|h| self.tree.closest_point_within(p, p.distance(h)))
            .unwrap_or_else(|| self.tree.closest_point(p))
    }

    /// The scan point paired with `p` (normal `n`) and the scan's normal
    /// there, or none (module docs); and the closest point, paired or not.
    fn pair(&self, p: DVec3, n: DVec3, cos_max: f64, hint: Option<DVec3>) -> (Option<(Pair, f64)>, DVec3) {
        let (q, f, d) = self.closest(p, hint);
        if !self.skin[f.idx()] {
            return (None, q);
        }
        let [a, b, c] = self.mesh.corners(f);
        let normal = (b - a).cross(c - a).normalize_or_zero();
        ((normal.dot(n) >= cos_max).then_some((Pair { point: q, normal }, d)), q)
    }
}

/// A scan point paired with a model point, and the scan's normal there.
#[derive(Debug, Clone, Copy)]
struct Pair {
    point: DVec3,
    normal: DVec3,
}

/// Pairs of model points with scan points, trimmed (module docs).
/// `hints` holds the closest scan points of the last call for the same
/// model points (empty the first time), which bound the searches
/// ([`WindingTree::closest_point_within`]: the same answers, found sooner),
/// and is updated.
fn pairs(
    scan: &Scan<'_>,
    points: &[DVec3],
    normals: &[DVec3],
    hints: &mut Vec<DVec3>,
    opts: &RegisterOptions,
) -> Vec<Option<Pair>> {
    let cos_max = opts.max_normal_angle_deg.to_radians().cos();
    let hinted = hints.len() == points.len();
    let (found, closest): (Vec<Option<(Pair, f64)>>, Vec<DVec3>) = points
        .par_iter()
        .zip(normals)
        .enumerate()
        .map(|(i, (&p, &n))| scan.pair(p, n, cos_max, hinted.then(|| hints[i])))
        .unzip();
    *hints = closest;
    let mut d: Vec<f64> = found.iter().flatten().map(|x| x.1).collect();
    if d.is_empty() {
        return vec![None; points.len()];
    }
    let mid = d.len() / 2;
    let median = *d.select_nth_unstable_by(mid, f64::total_cmp).1;
    let trim = (opts.trim_factor * median).max(opts.min_trim_mm / MM_PER_M);
    found.into_iter().map(|x| x.and_then(|(q, d)| (d <= trim).then_some(q))).collect()
}

/// Vertex normals of the model at `params` moved by `t`.
fn model_mesh(model: &BodyModel, params: &MannequinParams, t: DVec3) -> Result<TriMesh, MannequinError> {
    Ok(model.build(params)?.map_positions(|p| p + t)?)
}

/// The shape fit's state.
#[derive(Debug, Clone)]
struct Fit {
    params: MannequinParams,
    t: DVec3,
    cost: f64,
    /// The samples' closest scan points of the last round.
    hints: Vec<DVec3>,
}

/// The residual rows of one pair for a model point moved by `d` from its
/// scan point: point-to-plane `n·d`, and `w d` (module docs).
fn rows(pair: &Pair, d: DVec3, w: f64) -> [f64; 4] {
    [pair.normal.dot(d), w * d.x, w * d.y, w * d.z]
}

/// One ICP round: pairs, then LM steps.
fn round(
    sampled: &Sampled<'_>,
    scan: &Scan<'_>,
    vars: &[Var],
    fit: &mut Fit,
    opts: &RegisterOptions,
) -> Result<usize, RegisterError> {
    let normals_all = model_mesh(sampled.model, &fit.params, fit.t)?.vertex_normals();
    let normals: Vec<DVec3> = sampled.vertex.iter().map(|&v| normals_all[v]).collect();
    let points: Vec<DVec3> = sampled.positions(&fit.params)?.into_iter().map(|p| p + fit.t).collect();
    let pairs = pairs(scan, &points, &normals, &mut fit.hints, opts);
    let kept: Vec<(usize, Pair)> = pairs.iter().enumerate().filter_map(|(i, c)| c.map(|c| (i, c))).collect();
    if kept.len() < vars.len() * 3 {
        return Err(RegisterError::TooFewPairs { pairs: kept.len(), samples: points.len() });
    }
    let w = opts.point_to_point_weight;
    let x0: Vec<f64> = vars.iter().map(|v| v.get(&MannequinParams::default())).collect();
    let mu2 = opts.prior_weight_mm * opts.prior_weight_mm;
    let scale = MM_PER_M * MM_PER_M / kept.len() as f64;
    let cost_of = |pos: &[DVec3], t: DVec3, params: &MannequinParams| -> f64 {
        let data: f64 = kept
            .iter()
            .map(|&(i, c)| rows(&c, pos[i] + t - c.point, w).iter().map(|r| r * r).sum::<f64>())
            .sum::<f64>()
            * scale;
        let prior: f64 = vars.iter().zip(&x0).map(|(v, x0)| (v.get(params) - x0).powi(2)).sum::<f64>() * mu2;
        data + prior
    };
    let mut lambda = 1e-3;
    let mut pos = sampled.positions(&fit.params)?;
    fit.cost = cost_of(&pos, fit.t, &fit.params);
    for _ in 0..opts.lm_steps {
        // Jacobian columns: the parameters (forward differences), then t
        let cols: Vec<Vec<DVec3>> = vars
            .par_iter()
            .map(|&v| -> Result<Vec<DVec3>, MannequinError> {
                let col = sampled.column(&fit.params, v, opts.fd_step)?;
                Ok(kept.iter().map(|&(i, _)| col[i]).collect())
            })
            .collect::<Result<_, _>>()?;
        let n = vars.len() + 3;
        // the residual rows and their Jacobian, dense (4 rows a pair), then A = JᵀJ, b = −Jᵀr
        let m = 4 * kept.len();
        let mut jac = faer::Mat::<f64>::zeros(m, n);
        let mut res = faer::Mat::<f64>::zeros(m, 1);
        let axes = [DVec3::X, DVec3::Y, DVec3::Z];
        for (j, &(i, c)) in kept.iter().enumerate() {
            for (row, r) in rows(&c, pos[i] + fit.t - c.point, w).into_iter().enumerate() {
                res[(4 * j + row, 0)] = r;
            }
            for k in 0..n {
                let col = if k < vars.len() { cols[k][j] } else { axes[k - vars.len()] };
                for (row, v) in rows(&c, col, w).into_iter().enumerate() {
                    jac[(4 * j + row, k)] = v;
                }
            }
        }
        let jtj = jac.transpose() * &jac;
        let jtr = jac.transpose() * &res;
        let mut a: Vec<Vec<f64>> = (0..n).map(|k| (0..n).map(|l| jtj[(k, l)] * scale).collect()).collect();
        let mut b: Vec<f64> = (0..n).map(|k| -jtr[(k, 0)] * scale).collect();
        for (k, v) in vars.iter().enumerate() {
            a[k][k] += mu2;
            b[k] -= mu2 * (v.get(&fit.params) - x0[k]);
        }
        let mut improved = false;
        for _ in 0..6 {
            let mut damped = a.clone();
            for k in 0..n {
                damped[k][k] += lambda * a[k][k].max(1e-9);
            }
            let Some(step) = super::fit::solve_dense(damped, b.clone()) else { break };
            let mut p = fit.params.clone();
            for (k, v) in vars.iter().enumerate() {
                v.set(&mut p, v.get(&fit.params) + step[k]);
            }
            let t = fit.t + DVec3::new(step[n - 3], step[n - 2], step[n - 1]);
            let trial = sampled.positions(&p)?;
            let cost = cost_of(&trial, t, &p);
            if cost < fit.cost {
                fit.params = p;
                fit.t = t;
                fit.cost = cost;
                pos = trial;
                lambda = (lambda * 0.3).max(1e-6);
                improved = true;
                break;
            }
            lambda *= 10.0;
        }
        if !improved {
            break;
        }
    }
    Ok(kept.len())
}

/// Stature of the model at `params`, and its floor and centre (of the
/// samples' bounding box, which holds the model's extreme vertices).
fn extent(sampled: &Sampled<'_>, params: &MannequinParams) -> Result<(f64, f64, DVec3), MannequinError> {
    let pos = sampled.positions(params)?;
    let (lo, hi) = pos.iter().fold((DVec3::INFINITY, DVec3::NEG_INFINITY), |(lo, hi), &p| (lo.min(p), hi.max(p)));
    Ok((hi.y - lo.y, lo.y, 0.5 * (lo + hi)))
}

/// The rigid start for `gender` (module docs, step 1).
fn start(sampled: &Sampled<'_>, scan: &TriMesh, gender: f64, stature_scale: f64) -> Result<Fit, MannequinError> {
    let aabb = scan.aabb();
    let stature = aabb.size().y * stature_scale;
    let mut params = MannequinParams::default();
    params.macros.gender = gender;
    let (mut lo, mut hi) = (0.0, 1.0);
    for _ in 0..12 {
        params.macros.height = 0.5 * (lo + hi);
        if extent(sampled, &params)?.0 < stature {
            lo = params.macros.height;
        } else {
            hi = params.macros.height;
        }
    }
    params.macros.height = 0.5 * (lo + hi);
    let (_, floor, centre) = extent(sampled, &params)?;
    let sc = aabb.centre();
    let t = DVec3::new(sc.x - centre.x, aabb.min.y - floor, sc.z - centre.z);
    Ok(Fit { params, t, cost: f64::INFINITY, hints: Vec::new() })
}

/// Registers the embedded model to `scan` (module docs). `skin[f]` says
/// whether face `f` is scanned skin (false for a hole's fill); an empty
/// slice means every face is.
///
/// # Errors
/// [`RegisterError`].
pub fn register(
    model: &BodyModel,
    scan: &TriMesh,
    skin: &[bool],
    opts: &RegisterOptions,
) -> Result<Registration, RegisterError> {
    let skin = if skin.len() == scan.face_count() { skin.to_vec() } else { vec![true; scan.face_count()] };
    let scan_q = Scan { mesh: scan, tree: WindingTree::new(scan, &WindingOptions::default()), skin };
    let sampled = Sampled::new(model, opts.samples);
    let vars = variables();
    // gender is bimodal: a few rounds from each end, the better continued
    let mut starts = Vec::new();
    for gender in [0.0, 1.0] {
        let mut fit = start(&sampled, scan, gender, 1.0)?;
        for _ in 0..opts.start_rounds {
            round(&sampled, &scan_q, &vars, &mut fit, opts)?;
        }
        starts.push(fit);
    }
    starts.sort_by(|a, b| a.cost.total_cmp(&b.cost));
    // the better start continued; should it end in a local minimum (its samples farther from
    // the scan than the model's own fit of a body reaches), the other one too, then the better
    // gender from a taller start (a scan without its crown or soles reads short), the best kept
    let taller = |gender: f64| -> Result<Fit, RegisterError> {
        let mut fit = start(&sampled, scan, gender, opts.retry_stature_scale)?;
        for _ in 0..opts.start_rounds {
            round(&sampled, &scan_q, &vars, &mut fit, opts)?;
        }
        Ok(fit)
    };
    let better_gender = starts[0].params.macros.gender;
    let mut best: Option<(Fit, TriMesh, f64)> = None;
    let candidates = starts.into_iter().map(Ok).chain(std::iter::once_with(|| taller(better_gender)));
    for fit in candidates {
        let mut fit = fit?;
        for _ in 0..opts.rounds {
            round(&sampled, &scan_q, &vars, &mut fit, opts)?;
        }
        let shaped = model_mesh(model, &fit.params, fit.t)?;
        let rms = sample_residual(&sampled, &scan_q, &shaped, &fit, opts)?;
        if best.as_ref().is_none_or(|b| rms < b.2) {
            best = Some((fit, shaped, rms));
        }
        if best.as_ref().is_some_and(|b| b.2 <= opts.retry_above_mm) {
            break;
        }
    }
    let Some((fit, shaped, shape_rms_mm)) = best else {
        return Err(RegisterError::TooFewPairs { pairs: 0, samples: sampled.vertex.len() });
    };
    let surface = refine(&scan_q, shaped, opts)?;
    let (rms_mm, p95_mm) = residual(&scan_q, &surface, opts);
    if rms_mm > opts.max_rms_mm || p95_mm > opts.max_p95_mm {
        return Err(RegisterError::Residual {
            rms_mm,
            p95_mm,
            max_rms_mm: opts.max_rms_mm,
            max_p95_mm: opts.max_p95_mm,
        });
    }
    let found = hm08_landmarks(model, &surface, &opts.landmarks)?;
    let mut landmarks = Landmarks::default();
    let mut confidence = BTreeMap::new();
    for (id, p) in found.points {
        let (q, _, d) = scan_q.tree.closest_point(p);
        landmarks.points.insert(id, q);
        confidence.insert(id, (-(d * MM_PER_M) / opts.confidence_scale_mm).exp());
    }
    Ok(Registration {
        surface,
        params: fit.params,
        landmarks,
        report: RegistrationReport { rms_mm, p95_mm, shape_rms_mm, confidence },
    })
}

/// RMS distance of the samples' kept pairs after the shape fit, mm (the
/// model's side of the residual: no tree of the model is built for it).
fn sample_residual(
    sampled: &Sampled<'_>,
    scan: &Scan<'_>,
    shaped: &TriMesh,
    fit: &Fit,
    opts: &RegisterOptions,
) -> Result<f64, MannequinError> {
    let normals_all = shaped.vertex_normals();
    let normals: Vec<DVec3> = sampled.vertex.iter().map(|&v| normals_all[v]).collect();
    let points: Vec<DVec3> = sampled.positions(&fit.params)?.into_iter().map(|p| p + fit.t).collect();
    let d: Vec<f64> = pairs(scan, &points, &normals, &mut fit.hints.clone(), opts)
        .iter()
        .zip(&points)
        .filter_map(|(c, p)| c.map(|c| c.point.distance(*p) * MM_PER_M))
        .collect();
    Ok(if d.is_empty() { f64::INFINITY } else { (d.iter().map(|x| x * x).sum::<f64>() / d.len() as f64).sqrt() })
}

/// The non-rigid refinement (module docs, step 3).
fn refine(scan: &Scan<'_>, mesh: TriMesh, opts: &RegisterOptions) -> Result<TriMesh, RegisterError> {
    let n = mesh.vertex_count();
    // the graph Laplacian's off-diagonal pattern, each edge once
    let mut edges: Vec<(u32, u32)> = mesh
        .triangles()
        .iter()
        .flat_map(|t| (0..3).map(move |k| (t[k].0.min(t[(k + 1) % 3].0), t[k].0.max(t[(k + 1) % 3].0))))
        .collect();
    edges.sort_unstable();
    edges.dedup();
    let mut degree = vec![0.0; n];
    for &(a, b) in &edges {
        degree[a as usize] += 1.0;
        degree[b as usize] += 1.0;
    }
    let lambda = opts.smoothness;
    let mut mesh = mesh;
    let mut hints = Vec::new();
    for _ in 0..opts.refine_rounds {
        let normals = mesh.vertex_normals();
        let targets = pairs(scan, mesh.positions(), &normals, &mut hints, opts);
        let mut triplets: Vec<Triplet<usize, usize, f64>> = Vec::with_capacity(n + 2 * edges.len());
        for (v, c) in targets.iter().enumerate() {
            let w = if c.is_some() { 1.0 } else { 0.0 };
            // a tiny anchor keeps an isolated vertex without pairs determined
            triplets.push(Triplet::new(v, v, w + lambda * degree[v] + 1e-9));
        }
        for &(a, b) in &edges {
            triplets.push(Triplet::new(a as usize, b as usize, -lambda));
            triplets.push(Triplet::new(b as usize, a as usize, -lambda));
        }
        let Ok(matrix) = SparseColMat::<usize, f64>::try_new_from_triplets(n, n, &triplets) else { break };
        let Ok(llt) = matrix.sp_cholesky(Side::Lower) else { break };
        let rhs = faer::Mat::from_fn(n, 3, |v, k| match targets[v] {
            Some(c) => (c.point - mesh.positions()[v])[k],
            None => 0.0,
        });
        let d = llt.solve(rhs);
        let moved: Vec<DVec3> = mesh
            .positions()
            .iter()
            .enumerate()
            .map(|(v, &p)| p + DVec3::new(d[(v, 0)], d[(v, 1)], d[(v, 2)]))
            .collect();
        mesh = TriMesh::new(moved, mesh.triangles().to_vec()).map_err(MannequinError::from)?;
    }
    Ok(mesh)
}

/// RMS and 95th percentile of the distance from scan skin to `surface`, mm.
fn residual(scan: &Scan<'_>, surface: &TriMesh, opts: &RegisterOptions) -> (f64, f64) {
    let tree = WindingTree::new(surface, &WindingOptions::default());
    let faces: Vec<FaceId> = (0..scan.mesh.face_count()).filter(|&f| scan.skin[f]).map(FaceId::from).collect();
    let stride = (faces.len() / opts.residual_samples.max(1)).max(1);
    let mut d: Vec<f64> = faces
        .par_iter()
        .step_by(stride)
        .map(|&f| {
            let [a, b, c] = scan.mesh.corners(f);
            tree.closest_point((a + b + c) / 3.0).2 * MM_PER_M
        })
        .collect();
    if d.is_empty() {
        return (f64::INFINITY, f64::INFINITY);
    }
    let rms = (d.iter().map(|x| x * x).sum::<f64>() / d.len() as f64).sqrt();
    let at = ((d.len() as f64 * 0.95).ceil() as usize).clamp(1, d.len()) - 1;
    let p95 = *d.select_nth_unstable_by(at, f64::total_cmp).1;
    (rms, p95)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::body::derive::{derive_features, DeriveOptions};
    use crate::mannequin::population::{sample_population, scan_like};

    #[test]
    fn a_scan_like_population_body_is_registered_and_its_landmarks_found() {
        let model = BodyModel::embedded().expect("model");
        let body = &sample_population(14, 17)[12];
        let mesh = model.build(&body.params).expect("body");
        let truth = hm08_landmarks(model, &mesh, &Hm08LandmarkOptions::default()).expect("landmarks");
        let scan = scan_like(&mesh, 30_000, 1e-3, 5).expect("scan");
        let reg = register(model, &scan, &[], &RegisterOptions::default()).expect("registers");
        assert!(reg.report.rms_mm < 2.0 && reg.report.p95_mm < 5.0, "{:?}", reg.report);
        // the model's rings sit where its topology puts them: different parameters that give the
        // same surface put a ring a few centimetres higher or lower, and the crotch (the lowest
        // point of a flat saddle) slides along it
        let mut errors: Vec<f64> =
            truth.points.iter().map(|(id, p)| reg.landmarks.points[id].distance(*p) * MM_PER_M).collect();
        errors.sort_by(f64::total_cmp);
        assert_eq!(errors.len(), truth.points.len());
        assert!(errors[errors.len() / 2] < 12.0 && errors[errors.len() - 1] < 45.0, "{errors:?}");
        assert!(reg.report.confidence.values().all(|c| (0.0..=1.0).contains(c)));
        derive_features(scan, &reg.landmarks, &DeriveOptions::default()).expect("a feature body");
    }

    #[test]
    fn a_scan_the_model_cannot_fit_is_refused_with_its_residual() {
        let model = BodyModel::embedded().expect("model");
        let mesh = model.build(&MannequinParams::default()).expect("body");
        // a block of the body's size: no body shape fits it
        let aabb = mesh.aabb();
        let block = TriMesh::icosahedron().map_positions(|p| aabb.centre() + p * aabb.size() * 0.3).expect("mesh");
        match register(model, &block, &[], &RegisterOptions::default()) {
            Err(RegisterError::Residual { rms_mm, .. }) => assert!(rms_mm > 6.0),
            Err(RegisterError::TooFewPairs { .. }) => {}
            other => panic!("{:?}", other.map(|r| r.report)),
        }
    }
}
