//! The three grading flows as plain functions: data in, artefacts out (no
//! HTTP, no async). The service runs them on its bounded pool; batch jobs
//! run them on the job worker.
//!
//! - [`size_chart`]: one mannequin per size row — the base size fitted, every
//!   other size graded from its body by seed 003 profile scaling
//!   ([`crate::mannequin::fit::fit_graded`]: one body growing with the
//!   chart) —, every template graded on every size, the
//!   graded nest and grade rules per template (issue #5), per-size meshes and
//!   patterns, and the fit report. The base size is graded first and its
//!   dart plan carried to every other size (issue #14: one dart plan per
//!   run, [`crate::pattern::garment::DartPlan`]); each template's nest is
//!   trued at its corners outwards from the base size
//!   ([`crate::pattern::true_up`]) before the per-size patterns, the nest and
//!   the rules are written, and the report says by how much
//!   (`nest_truing`).
//! - [`scan`]: one body scan, one or more templates. A scan comes as a
//!   scanner gives it (issue #17): repaired, its units, up axis and facing
//!   found, and its landmarks — where the request lacks any the vocabulary
//!   requires — read off the embedded model registered to it
//!   ([`grade3d_core::scan`]); the report says what was done. Its darts
//!   start from each template's block ([`crate::blocks`], issue #15):
//!   carried where they hold on the body, decided on it where not.
//! - [`bodies`]: many scans × templates (the batch flow's bodies part); the
//!   base body's darts start from the blocks, as a scan's, and with several
//!   bodies the base body's dart plan is carried to the others.
//!
//! Determinism: every artefact is a function of the inputs only — the base
//! size first, then the others (side by side on rayon's global pool, each
//! from the base size's body and plans alone); the artefacts and the report
//! list sizes and templates in request order, and the report carries no wall
//! times (those go to [`Outcome::timings`], outside the artefacts).

use std::collections::BTreeMap;
use std::sync::Arc;
use std::time::Instant;

use serde::{Deserialize, Serialize};

use crate::blocks::BlockCache;
use crate::body::derive::{FeatureError, Landmarks};
use crate::body::feature::FeatureBody;
use crate::body::frame::FrameHints;
use crate::body::measure::{measure, MeasureOptions};
use crate::collide::cache::{BodyKey, Obstacle, ObstacleCache};
use crate::collide::render::{RenderError, RenderOptions, Renderer};
use crate::geom::mesh::TriMesh;
use crate::geom::winding::WindingOptions;
use crate::io::gltf::{read_soup, write_glb, GlbAttribute, GltfError, GltfReadOptions};
use crate::io::landmarks::{parse_landmarks, LandmarkFileError};
use crate::mannequin::fit::{fit_graded, fit_size, FitError, FitOptions, FittedMannequin};
use crate::mannequin::model::{BodyModel, MannequinError};
use crate::mannequin::size_chart::{Sex, SizeChart};
use crate::pattern::export::rul::{self, Created};
use crate::pattern::export::{dxf, svg, ExportError};
use crate::pattern::garment::{DartPlan, DartSource};
use crate::pattern::grade::{grade_rules, nests, GradeError};
use crate::pattern::piece::PatternPiece;
use crate::pattern::true_up::{true_nest, TrueOptions, TrueReport};
use crate::pipeline::{grade_with_darts, GradeOptions, Graded, PipelineError};
use crate::report::{BodiesReport, BodyReport, Flow, MannequinReport, Report, SizeChartReport, SizeReport};
use crate::store::Entry;
use crate::template::format::Template;
use crate::template::from_garment::DesignBody;
use grade3d_core::report::{fit_report, FitReport, FitReportError, FitReportOptions, FitStep, GarmentReport};
use grade3d_core::scan::{scan_body, ScanError, ScanOptions, ScanReport};

/// Why a flow failed. Client-caused variants name the offending input.
#[derive(Debug, thiserror::Error)]
pub enum WorkError {
    /// The embedded body model could not be loaded (internal).
    #[error(transparent)]
    Model(#[from] MannequinError),
    /// No mannequin could be fitted to a size row.
    #[error("size `{size}`: {source}")]
    Fit {
        /// The size label.
        size: String,
        /// Why.
        source: FitError,
    },
    /// The scan is not a usable glTF body.
    #[error("scan `{body}`: {source}")]
    Scan {
        /// Which body (its name in the request).
        body: String,
        /// Why.
        source: GltfError,
    },
    /// The landmarks document is invalid.
    #[error("landmarks of `{body}`: {source}")]
    Landmarks {
        /// Which body.
        body: String,
        /// Why.
        source: LandmarkFileError,
    },
    /// A scan could not be repaired, framed or registered.
    #[error("body `{body}`: {source}")]
    ScanBody {
        /// Which body.
        body: String,
        /// Why (never [`ScanError::Feature`]: that is [`WorkError::Feature`]).
        source: ScanError,
    },
    /// The feature model of a scan could not be derived.
    #[error("body `{body}`: {source}")]
    Feature {
        /// Which body.
        body: String,
        /// Why.
        source: FeatureError,
    },
    /// The scan has more vertices than the service accepts.
    #[error("body `{body}` has {vertices} vertices; at most {max} are accepted")]
    TooManyVertices {
        /// Which body.
        body: String,
        /// Its vertex count.
        vertices: usize,
        /// The limit.
        max: usize,
    },
    /// A template could not be graded onto a body.
    #[error("template `{template}` on `{size}`: {source}")]
    Grade {
        /// Template name.
        template: String,
        /// Size or body name.
        size: String,
        /// Why.
        source: PipelineError,
    },
    /// The depth maps could not be rendered (internal).
    #[error(transparent)]
    Render(#[from] RenderError),
    /// Nests or grade rules failed.
    #[error("grading `{template}`: {source}")]
    Nest {
        /// Template name.
        template: String,
        /// Why.
        source: GradeError,
    },
    /// The base size is not one of the chart's sizes.
    #[error("base size `{0}` is not a size of the chart")]
    UnknownBaseSize(String),
    /// An export failed.
    #[error(transparent)]
    Export(#[from] ExportError),
    /// Writing the garment GLB failed.
    #[error("garment GLB: {0}")]
    GarmentGlb(GltfError),
    /// The fit report of a garment could not be made (internal).
    #[error("fit report: {0}")]
    FitReport(#[from] FitReportError),
    /// A JSON artefact did not serialise (internal; issue #16: it was
    /// written as an empty artefact).
    #[error("{what} did not serialise: {source}")]
    Serialise {
        /// The artefact.
        what: String,
        /// Why.
        source: serde_json::Error,
    },
}

/// `value` as JSON (`pretty`: indented); one that does not serialise is a
/// [`WorkError::Serialise`] naming `what`, never an empty artefact.
///
/// # Errors
/// [`WorkError::Serialise`].
pub fn json_bytes(what: &str, value: &impl Serialize, pretty: bool) -> Result<Vec<u8>, WorkError> {
    let bytes = if pretty { serde_json::to_vec_pretty(value) } else { serde_json::to_vec(value) };
    bytes.map_err(|source| WorkError::Serialise { what: what.to_owned(), source })
}

/// One downloadable result.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Artefact {
    /// File name, unique within its outcome (`straight-skirt-8.pattern.svg`).
    pub name: String,
    /// Media type.
    pub media_type: &'static str,
    /// The bytes.
    pub bytes: Vec<u8>,
}

/// What a flow returns.
#[derive(Debug, Clone, Default)]
pub struct Outcome {
    /// The report (also among the artefacts as `report.json`).
    pub report: serde_json::Value,
    /// Every artefact, in a deterministic order.
    pub artefacts: Vec<Artefact>,
    /// Wall time per stage over the whole flow, ms (not part of any artefact).
    pub timings: BTreeMap<String, f64>,
}

/// Knobs of the flows.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct WorkOptions {
    /// Most vertices of a scan. Default 500 000.
    pub max_scan_vertices: usize,
    /// Grading knobs.
    pub grade: GradeOptions,
    /// Depth maps.
    pub render: RenderOptions,
    /// Truing the size-chart flow's nests ([`crate::pattern::true_up`]).
    pub true_nest: TrueOptions,
    /// Reading a scan: repair, frame, automatic landmarks, derivation.
    pub scan: ScanOptions,
    /// A scan's (or a body run's base body's) darts start from the
    /// template's block ([`crate::blocks`]: its dart plan on the body it
    /// was designed on), carried where they hold on the body; false: decided
    /// on the body, searched where a piece strains. Default true.
    pub block_darts: bool,
}

impl Default for WorkOptions {
    fn default() -> Self {
        Self {
            max_scan_vertices: 500_000,
            grade: GradeOptions::default(),
            render: RenderOptions::default(),
            true_nest: TrueOptions::default(),
            scan: ScanOptions::default(),
            block_darts: true,
        }
    }
}

/// Builds a template's design body for its block ([`WorkContext::blocks`]):
/// the service resolves every kind ([`crate::edit::design_body`], a stored
/// avatar from its store); [`DesignBodyResolver::core`] all but a stored
/// avatar.
#[derive(Clone)]
pub struct DesignBodyResolver(
    /// The resolution; its error in words, for the log.
    pub Arc<ResolveDesignBody>,
);

/// What a [`DesignBodyResolver`] runs.
pub type ResolveDesignBody = dyn Fn(&DesignBody) -> Result<Arc<FeatureBody>, String> + Send + Sync;

impl DesignBodyResolver {
    /// The core's ([`crate::template::from_garment::design_body`]): a stored
    /// avatar is not reachable (`grade3d grade` has no store).
    pub fn core() -> Self {
        Self(Arc::new(|which: &DesignBody| match which {
            DesignBody::Reference => crate::edit::reference_body(),
            _ => crate::template::from_garment::design_body(which).map(Arc::new).map_err(|e| e.to_string()),
        }))
    }
}

impl std::fmt::Debug for DesignBodyResolver {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str("DesignBodyResolver")
    }
}

/// What the flows share: the depth-map renderer (optional: without one,
/// grading runs without collision avoidance and the report says so) and the per-body
/// obstacle cache (used for mannequins only: scans are personal data and
/// nothing derived from them outlives the request).
#[derive(Debug)]
pub struct WorkContext {
    /// The process's one depth-map renderer (wgpu, or the CPU rasteriser).
    pub renderer: Option<Arc<Renderer>>,
    /// Depth maps and winding trees of mannequins.
    pub obstacles: Arc<ObstacleCache>,
    /// The templates' blocks ([`crate::blocks`]).
    pub blocks: Arc<BlockCache>,
    /// The templates' design bodies, their blocks' bodies.
    pub design_bodies: DesignBodyResolver,
    /// Knobs.
    pub opts: WorkOptions,
}

/// Stage names, as reported in timings and progress.
pub mod stage {
    /// Fitting mannequins to size rows.
    pub const FIT: &str = "fit";
    /// Reading a scan and deriving its features.
    pub const BODY: &str = "body";
    /// Rendering depth maps and building the winding tree.
    pub const OBSTACLE: &str = "obstacle";
    /// Decoding templates onto bodies.
    pub const DECODE: &str = "decode";
    /// Subdivision with collision avoidance.
    pub const REFINE: &str = "refine";
    /// Keeping every vertex and triangle of the garment outside the body.
    pub const CLEAR: &str = "clear";
    /// Panels, flattening, pieces.
    pub const PATTERN: &str = "pattern";
    /// Making the templates' blocks ([`crate::blocks`]; once per process
    /// and template, so in a running service only the first request with a
    /// template not yet blocked spends it).
    pub const BLOCK: &str = "block";
    /// Writing SVG, DXF, GLB, JSON.
    pub const EXPORT: &str = "export";
}

/// Progress callback: `(stage, done, total)` in grades.
pub type Progress<'a> = &'a (dyn Fn(&str, usize, usize) + Sync);

struct Timer(BTreeMap<String, f64>);

impl Timer {
    fn add(&mut self, stage: &str, since: Instant) {
        self.add_ms(stage, since.elapsed().as_secs_f64() * 1e3);
    }

    fn add_ms(&mut self, stage: &str, ms: f64) {
        *self.0.entry(stage.to_owned()).or_default() += ms;
    }
}

impl WorkContext {
    /// The body as an obstacle (none without a renderer), from the cache or built
    /// and, with `cache`, kept there; its time goes to `timer`'s obstacle stage.
    fn obstacle(&self, mesh: &TriMesh, cache: bool, timer: &mut Timer) -> Result<Option<Arc<Obstacle>>, WorkError> {
        let start = Instant::now();
        let Some(renderer) = &self.renderer else { return Ok(None) };
        // the winding tree is built on the CPU while the maps render (issue #15)
        let build = || Obstacle::build(mesh, renderer.as_ref(), &self.opts.render, &WindingOptions::default());
        let obstacle = if cache {
            self.obstacles.get_or_build(BodyKey::of(mesh, &self.opts.render), build)?
        } else {
            Arc::new(build()?)
        };
        timer.add(stage::OBSTACLE, start);
        Ok(Some(obstacle))
    }

    /// The block of each of `templates`, in order ([`crate::blocks`]): kept,
    /// or made now and kept; `None` for a template with none (no renderer
    /// — the block is a grade with collision —, [`WorkOptions::block_darts`]
    /// off, or a template that cannot be graded on the reference body).
    pub fn blocks(&self, templates: &[Template]) -> Vec<Option<Arc<DartPlan>>> {
        templates
            .iter()
            .map(|t| {
                if !self.opts.block_darts || self.renderer.is_none() {
                    return None;
                }
                self.blocks.get_or_build(t, || self.block_of(t))
            })
            .collect()
    }

    /// `t`'s block: graded on its design body (the reference body unless
    /// it names another), its darts decided there. A stored avatar's
    /// obstacle is not cached (the block is). (Why not, in words, for the
    /// log: it is never a request's error.)
    fn block_of(&self, t: &Template) -> Result<DartPlan, String> {
        let which = t.design_body.clone().unwrap_or_default();
        let body = (self.design_bodies.0)(&which)?;
        let cache = !matches!(which, DesignBody::Scan { .. });
        let obstacle = self.obstacle(&body.mesh, cache, &mut Timer(BTreeMap::new())).map_err(|e| e.to_string())?;
        crate::pipeline::block(t, &body, obstacle.as_deref(), &self.opts.grade)
            .map_err(|e| format!("graded on its design body {which:?}: {e}"))
    }
}

/// A body of a batch or scan request, before validation.
#[derive(Debug, Clone)]
pub struct BodyInput<'a> {
    /// Its name (the size label of its results).
    pub name: &'a str,
    /// GLB or glTF with embedded buffers.
    pub glb: &'a [u8],
    /// Landmarks JSON, if given (all, some or none of the vocabulary's
    /// points: the rest are found by registration).
    pub landmarks: Option<&'a str>,
    /// What the request states of the scan's units, up axis and facing.
    pub hints: FrameHints,
}

/// A scan read: its feature model and what reading it did.
#[derive(Debug, Clone)]
pub struct ReadBody {
    /// The feature model.
    pub body: FeatureBody,
    /// Repair, frame and landmarks, for the report.
    pub scan: ScanReport,
}

/// Reads and checks a scan, repairs it, brings it into the body frame,
/// finds the landmarks it lacks and derives its feature model
/// ([`grade3d_core::scan::scan_body`]).
///
/// # Errors
/// [`WorkError::Scan`], [`WorkError::TooManyVertices`], [`WorkError::Landmarks`],
/// [`WorkError::ScanBody`], [`WorkError::Feature`].
pub fn read_body(input: &BodyInput<'_>, opts: &WorkOptions) -> Result<ReadBody, WorkError> {
    let name = input.name.to_owned();
    let (positions, triangles) = read_soup(input.glb, &GltfReadOptions::default())
        .map_err(|source| WorkError::Scan { body: name.clone(), source })?;
    if positions.len() > opts.max_scan_vertices {
        return Err(WorkError::TooManyVertices { body: name, vertices: positions.len(), max: opts.max_scan_vertices });
    }
    let lm: Option<Landmarks> = input
        .landmarks
        .map(parse_landmarks)
        .transpose()
        .map_err(|source| WorkError::Landmarks { body: name.clone(), source })?;
    match scan_body(&positions, &triangles, &input.hints, lm.as_ref(), &opts.scan) {
        Ok((body, scan)) => Ok(ReadBody { body, scan }),
        Err(ScanError::Feature(source)) => Err(WorkError::Feature { body: name, source }),
        Err(source) => Err(WorkError::ScanBody { body: name, source }),
    }
}

/// Indices `0..total`, `base` first, then the others in order (a run grades
/// its base size first: its dart plan is carried to the others).
fn base_first(total: usize, base: usize) -> impl Iterator<Item = usize> {
    std::iter::once(base).chain((0..total).filter(move |&i| i != base))
}

/// A run's bodies in three steps, on rayon's global pool (one process-wide
/// budget of CPU threads, shared by every request):
/// 1. `prepare_base` on the base index `base`: its body (fitted, or read)
///    and obstacle, what every other body is prepared from;
/// 2. `grade` on it with no dart plans — its plans become the run's — while
///    as many other bodies as the pool has threads are prepared alongside
///    (`prepare_rest`, from the base's preparation alone; issue #15: the
///    base's grade leaves cores idle, and a prepared body holds its
///    obstacle, about 15 MB, so only a few go ahead);
/// 3. every other body prepared (unless it went ahead) and graded with the
///    base's plans, side by side.
///
/// Each body has its own stage timer, summed into `timer`, and gets
/// `(index, how many bodies were started before it)`, the latter for
/// progress. Results by index; the first failure in the sequential order
/// (the base, then the others in index order) is the one returned, as one
/// body after another would report it.
fn base_then_rest<P: Send + Sync, R: Send>(
    total: usize,
    base: usize,
    timer: &mut Timer,
    prepare_base: impl FnOnce(usize, &mut Timer) -> Result<P, WorkError>,
    prepare_rest: impl Fn((usize, usize), &P, &mut Timer) -> Result<P, WorkError> + Sync,
    grade: impl Fn((usize, usize), &P, Option<&[DartPlan]>, &mut Timer) -> Result<Done<R>, WorkError> + Sync,
) -> Result<Vec<Option<Done<R>>>, WorkError> {
    use rayon::prelude::*;
    use std::sync::atomic::{AtomicUsize, Ordering};
    let mut done: Vec<Option<Done<R>>> = (0..total).map(|_| None).collect();
    let mut order = base_first(total, base).filter(|&i| i < total);
    let Some(b) = order.next() else { return Ok(done) };
    let others: Vec<usize> = order.collect();
    let started = AtomicUsize::new(1);
    let p_base = prepare_base(b, timer)?;
    // one other body prepared: its ordinal, its preparation and its timer so far
    let prepare = |i: usize| {
        let at = (i, started.fetch_add(1, Ordering::Relaxed));
        let mut own = Timer(BTreeMap::new());
        let p = prepare_rest(at, &p_base, &mut own);
        (at, p, own)
    };
    let (early, _) = others.split_at(rayon::current_num_threads().min(others.len()));
    let (base_done, early) = rayon::join(
        || grade((b, 0), &p_base, None, timer),
        || early.par_iter().map(|&i| prepare(i)).collect::<Vec<_>>(),
    );
    let base_done = base_done?;
    let plans = plans_of(&base_done.0);
    done[b] = Some(base_done);
    let mut early = early.into_iter();
    let prepared: Vec<_> = others.iter().map(|_| early.next()).collect();
    let results: Vec<Result<(Done<R>, Timer), WorkError>> = others
        .par_iter()
        .zip(prepared)
        .map(|(&i, pre)| {
            let (at, p, mut own) = pre.unwrap_or_else(|| prepare(i));
            grade(at, &p?, Some(&plans), &mut own).map(|t| (t, own))
        })
        .collect();
    for (&i, result) in others.iter().zip(results) {
        let (t, own) = result?;
        for (stage, ms) in own.0 {
            timer.add_ms(&stage, ms);
        }
        done[i] = Some(t);
    }
    Ok(done)
}

/// The dart plan of each template's grade, in template order (a run's base size).
fn plans_of(graded: &[(String, Graded, FitReport)]) -> Vec<DartPlan> {
    graded.iter().map(|(_, g, _)| g.pattern.dart_plan.clone()).collect()
}

/// A body prepared for grading: its feature model (and, for a chart size,
/// its fit) and its obstacle.
type Prepared<B> = (B, Option<Arc<Obstacle>>);

/// One graded body of a run, kept until the run is reported in request
/// order: its grades (template name, grade, fit figures), its report part
/// (residuals or measurements) and its artefacts.
type Done<R> = (Vec<(String, Graded, FitReport)>, R, Vec<Artefact>);

/// Grades every template on one body and writes its per-size artefacts;
/// `plans[i]`, where given, is template `i`'s dart plan from the run's base
/// size (unless [`crate::pattern::garment::PatternOptions::search_every_size`]);
/// without plans, `blocks[i]`, where given, is template `i`'s block
/// ([`crate::blocks`]), else its darts are decided on this body. With
/// [`Patterns::Later`] the pattern artefacts are left to [`write_patterns`]
/// (a size chart's, once its nests are trued).
#[expect(clippy::too_many_arguments, reason = "one body of a run: its inputs, the run's plans, timer and artefacts")]
fn grade_body(
    ctx: &WorkContext,
    templates: &[Template],
    body: &FeatureBody,
    obstacle: Option<&Obstacle>,
    size: &str,
    plans: Option<&[DartPlan]>,
    blocks: &[Option<Arc<DartPlan>>],
    patterns: Patterns,
    timer: &mut Timer,
    out: &mut Vec<Artefact>,
) -> Result<Vec<(String, Graded, FitReport)>, WorkError> {
    let mut graded = Vec::with_capacity(templates.len());
    let carry = !ctx.opts.grade.pattern.search_every_size;
    for (i, t) in templates.iter().enumerate() {
        let darts = match (plans, blocks.get(i).and_then(Option::as_deref)) {
            (Some(p), _) => p.get(i).filter(|_| carry).map_or(DartSource::Decide, DartSource::Run),
            (None, Some(block)) => DartSource::Block(block),
            (None, None) => DartSource::Decide,
        };
        let g = grade_with_darts(t, body, obstacle, size, &ctx.opts.grade, darts)
            .map_err(|source| WorkError::Grade { template: t.name.clone(), size: size.to_owned(), source })?;
        timer.add_ms(stage::DECODE, g.timings.decode_ms);
        timer.add_ms(stage::REFINE, g.timings.refine_ms);
        timer.add_ms(stage::CLEAR, g.timings.clear_ms);
        timer.add_ms(stage::PATTERN, g.timings.pattern_ms);
        let start = Instant::now();
        if patterns == Patterns::Now {
            out.extend(pattern_artefacts(&t.name, size, &g)?);
        }
        let (glb, fit) = garment_glb(t, &g, body, obstacle)?;
        out.push(Artefact { name: garment_glb_name(&t.name, size), media_type: "model/gltf-binary", bytes: glb });
        timer.add(stage::EXPORT, start);
        graded.push((t.name.clone(), g, fit));
    }
    Ok(graded)
}

/// When [`grade_body`] writes a body's pattern artefacts.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Patterns {
    /// With the rest of the body's artefacts.
    Now,
    /// Not at all: [`write_patterns`] writes them later, each template's
    /// before its garment GLB (a size chart's, once its nests are trued:
    /// issue #15, a size's patterns were written twice, the second time
    /// one size after another).
    Later,
}

/// The pattern of one template on one size: SVG, DXF (AAMA and AccuMark) and JSON.
fn pattern_artefacts(template: &str, size: &str, g: &Graded) -> Result<Vec<Artefact>, WorkError> {
    let stem = format!("{template}-{size}");
    let pieces = &g.pattern.pieces;
    Ok(vec![
        Artefact {
            name: format!("{stem}.pattern.svg"),
            media_type: "image/svg+xml",
            bytes: svg::pieces_svg(pieces, &Default::default()).into_bytes(),
        },
        Artefact {
            name: format!("{stem}.pattern.dxf"),
            media_type: "image/vnd.dxf",
            bytes: dxf::pieces_dxf(template, pieces, &Default::default())?,
        },
        Artefact {
            name: format!("{stem}.pattern.accumark.dxf"),
            media_type: "image/vnd.dxf",
            bytes: dxf::pieces_dxf(template, pieces, &gerber())?,
        },
        Artefact {
            name: format!("{stem}.pattern.json"),
            media_type: "application/json",
            bytes: json_bytes(&format!("{stem}.pattern.json"), &g.pattern, false)?,
        },
    ])
}

/// One graded row of a size chart: its size, each template's grade (with its
/// fit report) and the row's artefacts.
type GradedRow = (String, Vec<(String, Graded, FitReport)>, Vec<Artefact>);

/// Trues every template's nest over the graded rows (chart order, `base`
/// their base row), the pieces it moved replaced in the rows' grades; per
/// template, what it did.
fn true_rows(
    templates: &[Template],
    rows: &mut [GradedRow],
    base: usize,
    opts: &TrueOptions,
) -> Vec<(String, TrueReport)> {
    let mut reports = Vec::with_capacity(templates.len());
    for (ti, t) in templates.iter().enumerate() {
        let mut sizes: Vec<(String, Vec<PatternPiece>)> =
            rows.iter().map(|(size, graded, _)| (size.clone(), graded[ti].1.pattern.pieces.clone())).collect();
        let report = true_nest(&mut sizes, base, opts);
        for ((size, graded, _), (_, pieces)) in rows.iter_mut().zip(sizes) {
            if report.moved.iter().any(|m| m.size == *size) {
                graded[ti].1.pattern.pieces = pieces;
            }
        }
        reports.push((t.name.clone(), report));
    }
    reports
}

/// Every row's pattern artefacts ([`Patterns::Later`]), each template's
/// before its garment GLB; the rows side by side on rayon's pool. The first
/// failure in row order is returned.
fn write_patterns(rows: &mut [GradedRow]) -> Result<(), WorkError> {
    use rayon::prelude::*;
    let written: Vec<Result<(), WorkError>> = rows
        .par_iter_mut()
        .map(|(size, graded, out)| {
            for (template, g, _) in graded.iter() {
                let glb = garment_glb_name(template, size);
                let at = out.iter().position(|a| a.name == glb).unwrap_or(out.len());
                out.splice(at..at, pattern_artefacts(template, size, g)?);
            }
            Ok(())
        })
        .collect();
    written.into_iter().collect()
}

/// The name of a garment GLB artefact (the pattern artefacts of its size
/// are written before it, [`write_patterns`]).
fn garment_glb_name(template: &str, size: &str) -> String {
    format!("{template}-{size}.garment.glb")
}

/// The garment as GLB with the ease (distance to the body, mm) as a vertex
/// attribute, and its fit report (the core's [`fit_report`] step).
fn garment_glb(
    t: &Template,
    g: &Graded,
    body: &FeatureBody,
    obstacle: Option<&Obstacle>,
) -> Result<(Vec<u8>, FitReport), WorkError> {
    let mesh = g.mesh.to_tri_mesh().map_err(|e| WorkError::GarmentGlb(GltfError::Mesh(e)))?;
    let FitStep { ease_mm, report } = fit_report(t, g, body, obstacle, &FitReportOptions::default())?;
    let normals = mesh.vertex_normals();
    let ease_f32: Vec<f32> = ease_mm.iter().map(|&e| e as f32).collect();
    let glb = write_glb(&mesh, Some(&normals), &[GlbAttribute { name: "_EASE_MM", values: &ease_f32 }], "grade3d")
        .map_err(WorkError::GarmentGlb)?;
    Ok((glb, report))
}

/// The templates of a run by name and version, for the report.
fn template_entries(templates: &[Template]) -> Vec<Entry> {
    templates.iter().map(|t| Entry { name: t.name.clone(), version: t.version }).collect()
}

/// The DXF options of the Gerber AccuMark profile (strict R12: empty HEADER, no TABLES).
fn gerber() -> dxf::DxfOptions {
    dxf::DxfOptions { profile: dxf::DxfProfile::GerberAccuMark, ..Default::default() }
}

/// Nests, grade rules and their exports of one template over sizes (each
/// written side by side on rayon's pool: issue #15, they were the run's
/// serial tail).
fn graded_nest(
    template: &str,
    sizes: &[(String, Vec<PatternPiece>)],
    base: &str,
    created: Option<Created>,
) -> Result<Vec<Artefact>, WorkError> {
    let nest_err = |source| WorkError::Nest { template: template.to_owned(), source };
    let (nested, rules) = rayon::join(|| nests(sizes), || grade_rules(template, sizes, base));
    let (nested, rules) = (nested.map_err(nest_err)?, rules.map_err(nest_err)?);
    let ((svg, (dxf, accumark)), (csv, rul)) = rayon::join(
        || {
            rayon::join(
                || svg::nest_svg(template, &nested, &Default::default()).into_bytes(),
                || {
                    rayon::join(
                        || dxf::nest_dxf_with_rules(template, &nested, &rules, &Default::default()),
                        || dxf::nest_dxf_with_rules(template, &nested, &rules, &gerber()),
                    )
                },
            )
        },
        || {
            rayon::join(
                || rul::rules_table_csv(&rules),
                || rul::rules_rul_with(&rules, &rul::RulOptions { created, ..Default::default() }).into_bytes(),
            )
        },
    );
    Ok(vec![
        Artefact { name: format!("{template}.nest.svg"), media_type: "image/svg+xml", bytes: svg },
        Artefact { name: format!("{template}.nest.dxf"), media_type: "image/vnd.dxf", bytes: dxf? },
        Artefact { name: format!("{template}.nest.accumark.dxf"), media_type: "image/vnd.dxf", bytes: accumark? },
        Artefact { name: format!("{template}.rules.csv"), media_type: "text/csv", bytes: csv?.into_bytes() },
        Artefact {
            // named after the nest DXF whose `# n` texts it numbers, as CAD systems pair them
            name: format!("{template}.nest.rul"),
            media_type: "text/plain",
            bytes: rul,
        },
    ])
}

/// The garment reports of one body; each template's pieces join its sizes.
fn collect(
    graded: Vec<(String, Graded, FitReport)>,
    size: &str,
    per_template: &mut [Vec<(String, Vec<PatternPiece>)>],
) -> Vec<GarmentReport> {
    graded
        .into_iter()
        .zip(per_template.iter_mut())
        .map(|((name, mut g, fit), sizes)| {
            sizes.push((size.to_owned(), std::mem::take(&mut g.pattern.pieces)));
            GarmentReport::new(&name, g, fit)
        })
        .collect()
}

/// [`graded_nest`] of every template, timed as export.
fn graded_nests(
    templates: &[Template],
    per_template: &[Vec<(String, Vec<PatternPiece>)>],
    base: &str,
    created: Option<Created>,
    timer: &mut Timer,
    out: &mut Vec<Artefact>,
) -> Result<(), WorkError> {
    use rayon::prelude::*;
    let start = Instant::now();
    let written: Vec<Result<Vec<Artefact>, WorkError>> =
        templates.par_iter().zip(per_template).map(|(t, sizes)| graded_nest(&t.name, sizes, base, created)).collect();
    for w in written {
        out.extend(w?);
    }
    timer.add(stage::EXPORT, start);
    Ok(())
}

fn finish(report: Report, mut artefacts: Vec<Artefact>, timer: Timer) -> Result<Outcome, WorkError> {
    // through a Value: every object's keys in lexicographic order (module docs of [`crate::report`])
    let report =
        serde_json::to_value(&report).map_err(|source| WorkError::Serialise { what: "report.json".into(), source })?;
    let bytes = json_bytes("report.json", &report, true)?;
    artefacts.push(Artefact { name: "report.json".into(), media_type: "application/json", bytes });
    Ok(Outcome { report, artefacts, timings: timer.0 })
}

/// The size-chart flow (module docs). `base` is the grade rules' base size
/// (default: the middle row); `created` the `.RUL` files' creation stamp
/// (none: no date in them).
///
/// # Errors
/// [`WorkError`].
pub fn size_chart(
    ctx: &WorkContext,
    templates: &[Template],
    chart: &SizeChart,
    base: Option<&str>,
    created: Option<Created>,
    progress: Progress<'_>,
) -> Result<Outcome, WorkError> {
    let base = match base {
        Some(b) if chart.rows.iter().any(|r| r.size == b) => b.to_owned(),
        Some(b) => return Err(WorkError::UnknownBaseSize(b.to_owned())),
        None => chart.rows.get(chart.rows.len() / 2).map(|r| r.size.clone()).unwrap_or_default(),
    };
    let model = BodyModel::embedded()?;
    let mut timer = Timer(BTreeMap::new());
    let mut artefacts = Vec::new();
    let mut per_template: Vec<Vec<(String, Vec<PatternPiece>)>> = vec![Vec::new(); templates.len()];
    let mut sizes = Vec::new();
    let total = chart.rows.len();
    let fit_opts = FitOptions::for_sex(chart.sex);
    // the base size first: its dart plan is carried to every other size (one plan per run)
    let base_row = chart.rows.iter().position(|r| r.size == base).unwrap_or(0);
    // one size prepared (`done` sizes started before it): fitted (the base size) or graded from
    // the base size's body, and its obstacle
    let prepare_size = |(i, done): (usize, usize),
                        base_fit: Option<&FittedMannequin>,
                        timer: &mut Timer|
     -> Result<Prepared<FittedMannequin>, WorkError> {
        let row = &chart.rows[i];
        progress(stage::FIT, done, total);
        let start = Instant::now();
        let fitted = match base_fit {
            Some(b) if !fit_opts.independent_sizes => fit_graded(model, b, row, &fit_opts),
            _ => fit_size(model, row, &fit_opts),
        }
        .map_err(|source| WorkError::Fit { size: row.size.clone(), source })?;
        timer.add(stage::FIT, start);
        let obstacle = ctx.obstacle(&fitted.body.mesh, true, timer)?;
        Ok((fitted, obstacle))
    };
    // one size finished: every template graded on it with the base size's dart plans
    let grade_size = |(i, done): (usize, usize),
                      (fitted, obstacle): &Prepared<FittedMannequin>,
                      plans: Option<&[DartPlan]>,
                      timer: &mut Timer|
     -> Result<Done<MannequinReport>, WorkError> {
        let row = &chart.rows[i];
        progress(stage::REFINE, done, total);
        let mut out = Vec::new();
        let graded = grade_body(
            ctx,
            templates,
            &fitted.body,
            obstacle.as_deref(),
            &row.size,
            plans,
            &[],
            Patterns::Later,
            timer,
            &mut out,
        )?;
        let mannequin = MannequinReport {
            residuals: fitted.residuals.iter().map(|(id, r)| (id.as_str().to_owned(), r.into())).collect(),
            warnings: fitted.body.warnings.clone(),
        };
        Ok((graded, mannequin, out))
    };
    // the base size first: its body is the one every other size grows from, its dart plan
    // the run's (one plan per run); the others side by side
    let done_rows = base_then_rest(
        total,
        base_row,
        &mut timer,
        |i, timer| prepare_size((i, 0), None, timer),
        |at, (base_fit, _), timer| prepare_size(at, Some(base_fit), timer),
        grade_size,
    )?;
    // reported in the chart's order
    let mut rows = Vec::with_capacity(total);
    let mut mannequins = Vec::with_capacity(total);
    for (row, done) in chart.rows.iter().zip(done_rows) {
        let Some((graded, mannequin, out)) = done else { continue };
        rows.push((row.size.clone(), graded, out));
        mannequins.push(mannequin);
    }
    progress(stage::EXPORT, total, total);
    // the nests trued outwards from the base size before anything of them is written
    let start = Instant::now();
    let base_index = rows.iter().position(|r| r.0 == base).unwrap_or(0);
    let truing = true_rows(templates, &mut rows, base_index, &ctx.opts.true_nest);
    write_patterns(&mut rows)?;
    timer.add(stage::EXPORT, start);
    for ((size, graded, out), mannequin) in rows.into_iter().zip(mannequins) {
        artefacts.extend(out);
        let garments = collect(graded, &size, &mut per_template);
        sizes.push(SizeReport { size, mannequin, garments });
    }
    graded_nests(templates, &per_template, &base, created, &mut timer, &mut artefacts)?;
    let report = SizeChartReport {
        flow: Flow::SizeChart,
        sex: chart.sex,
        sex_source: chart.sex_source,
        figure: (chart.sex == Sex::Female).then_some(chart.figure),
        base_size: base,
        templates: template_entries(templates),
        collision_checked: ctx.renderer.is_some(),
        nest_truing: truing.into_iter().collect(),
        sizes,
    };
    finish(Report::SizeChart(report), artefacts, timer)
}

/// Grades every template on every body (scans); with more than one body the
/// nests and grade rules span the bodies, based on `base` (default: the
/// first body), the `.RUL` files stamped `created`.
///
/// # Errors
/// [`WorkError`].
pub fn bodies(
    ctx: &WorkContext,
    templates: &[Template],
    inputs: &[BodyInput<'_>],
    base: Option<&str>,
    created: Option<Created>,
    progress: Progress<'_>,
) -> Result<Outcome, WorkError> {
    let mut timer = Timer(BTreeMap::new());
    let mut artefacts = Vec::new();
    let mut per_template: Vec<Vec<(String, Vec<PatternPiece>)>> = vec![Vec::new(); templates.len()];
    let mut reports = Vec::new();
    let total = inputs.len();
    let base_at = base.and_then(|b| inputs.iter().position(|i| i.name == b)).unwrap_or(0);
    // the base body's darts start from each template's block
    let start = Instant::now();
    let blocks = ctx.blocks(templates);
    timer.add(stage::BLOCK, start);
    // one body prepared (`done` bodies started before it): read, its features derived, its obstacle
    let prepare_body = |(i, done): (usize, usize), timer: &mut Timer| -> Result<Prepared<ReadBody>, WorkError> {
        progress(stage::BODY, done, total);
        let start = Instant::now();
        let read = read_body(&inputs[i], &ctx.opts)?;
        timer.add(stage::BODY, start);
        let obstacle = ctx.obstacle(&read.body.mesh, false, timer)?;
        Ok((read, obstacle))
    };
    // one body finished: every template graded on it
    let grade_one = |(i, done): (usize, usize),
                     (ReadBody { body, scan }, obstacle): &Prepared<ReadBody>,
                     plans: Option<&[DartPlan]>,
                     timer: &mut Timer|
     -> Result<Done<BodyReport>, WorkError> {
        let input = &inputs[i];
        progress(stage::REFINE, done, total);
        let mut out = Vec::new();
        let graded = grade_body(
            ctx,
            templates,
            body,
            obstacle.as_deref(),
            input.name,
            plans,
            &blocks,
            Patterns::Now,
            timer,
            &mut out,
        )?;
        let about = BodyReport {
            body: input.name.to_owned(),
            measurements_m: measure(body, &MeasureOptions::default())
                .iter()
                .map(|(id, v)| (id.as_str().to_owned(), *v))
                .collect(),
            // what derivation accepted but a person should look at (issue #13: warnings, not refusals)
            warnings: body.warnings.clone(),
            scan: scan.clone(),
            garments: Vec::new(),
        };
        Ok((graded, about, out))
    };
    // the base body first (several bodies: a run): its dart plan is carried to the others
    let done_bodies = base_then_rest(
        total,
        base_at,
        &mut timer,
        |i, timer| prepare_body((i, 0), timer),
        |at, _, timer| prepare_body(at, timer),
        grade_one,
    )?;
    for (input, done) in inputs.iter().zip(done_bodies) {
        let Some((graded, about, out)) = done else { continue };
        artefacts.extend(out);
        let garments = collect(graded, input.name, &mut per_template);
        reports.push(BodyReport { garments, ..about });
    }
    if inputs.len() > 1 {
        let base = match base {
            Some(b) if inputs.iter().any(|i| i.name == b) => b.to_owned(),
            Some(b) => return Err(WorkError::UnknownBaseSize(b.to_owned())),
            None => inputs[0].name.to_owned(),
        };
        graded_nests(templates, &per_template, &base, created, &mut timer, &mut artefacts)?;
    }
    progress(stage::EXPORT, total, total);
    let report = BodiesReport {
        flow: if inputs.len() == 1 { Flow::Scan } else { Flow::Bodies },
        templates: template_entries(templates),
        collision_checked: ctx.renderer.is_some(),
        bodies: reports,
    };
    finish(Report::Bodies(report), artefacts, timer)
}

/// The scan flow: one body, one or more templates.
///
/// # Errors
/// [`WorkError`].
pub fn scan(ctx: &WorkContext, templates: &[Template], input: &BodyInput<'_>) -> Result<Outcome, WorkError> {
    bodies(ctx, templates, std::slice::from_ref(input), None, None, &|_, _, _| {})
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_json_artefact_that_does_not_serialise_is_an_internal_error_not_an_empty_file() {
        // regression (issue #16): `serde_json::to_vec(..).unwrap_or_default()` wrote an empty
        // artefact; the literal failing input: a map whose keys are not strings
        let bad: BTreeMap<(u8, u8), u8> = [((1, 2), 3)].into_iter().collect();
        let e = json_bytes("x.pattern.json", &bad, false).unwrap_err();
        assert!(matches!(&e, WorkError::Serialise { what, .. } if what == "x.pattern.json"), "{e}");
        let p = crate::problem::Problem::from(e);
        assert_eq!(p.status, 500);
        assert!(!p.detail.contains("key must be a string"), "{}", p.detail);
        assert_eq!(json_bytes("ok", &serde_json::json!({"a": 1}), false).unwrap(), br#"{"a":1}"#);
    }

    #[test]
    fn a_templates_block_is_decided_on_its_design_body() {
        let renderer = Renderer::new(crate::collide::render::RendererChoice::Auto).expect("a renderer");
        let asked = Arc::new(std::sync::Mutex::new(Vec::new()));
        let log = asked.clone();
        let ctx = WorkContext {
            renderer: Some(Arc::new(renderer)),
            obstacles: Arc::new(ObstacleCache::new(Default::default())),
            blocks: Default::default(),
            design_bodies: DesignBodyResolver(Arc::new(move |which: &DesignBody| {
                log.lock().unwrap().push(which.clone());
                (DesignBodyResolver::core().0)(which)
            })),
            opts: WorkOptions::default(),
        };
        let mut skirt = crate::template::library::builtin().unwrap().remove(0);
        skirt.design_body = Some(DesignBody::MakehumanBase);
        let mut unknown = skirt.clone();
        unknown.name = "on-an-avatar".into();
        unknown.design_body = Some(DesignBody::Scan { id: "gone".into() });
        let blocks = ctx.blocks(&[skirt, unknown]);
        assert!(blocks[0].is_some(), "the block on MakeHuman's base mesh");
        assert!(blocks[1].is_none(), "no block where the design body cannot be had (logged, not an error)");
        assert_eq!(*asked.lock().unwrap(), [DesignBody::MakehumanBase, DesignBody::Scan { id: "gone".into() }]);
    }
}
