//! The sewing pattern of one graded garment (issue #5): cut the refined mesh
//! into panels ([`super::panels`]), flatten each ([`super::flatten`]: LSCM
//! start, ARAP local/global on a once-factored sparse Cholesky), assemble
//! pattern pieces ([`super::assemble`]) and measure them.
//!
//! # Negotiated seams
//!
//! A seam is sewn from two pieces, so both sides must have the same length,
//! but nothing asks that length to be the 3D one: a pattern maker lets a
//! bias crotch seam take the length the cloth wants. Holding every seam at
//! its 3D length forces the curvature's strain into the piece (trousers
//! front on the male-average fixture: p95 6.4 % held, 4.1 % with its seams
//! free). So ([`PatternOptions::negotiate_seams`]) every panel is first
//! flattened with its seams free (soft springs only, like hems; dart legs
//! held equal). Along each seam, segment by segment between consecutive
//! template nodes (where the notches sit), the two sides took free lengths
//! `L_a`, `L_b`; both are held at `L = (w_a L_a + w_b L_b)/(w_a + w_b)`,
//! each edge scaled from its own free length `ℓ′_free`:
//! `ℓ′ = ℓ′_free L / L_side` ([`flatten_with_sewn_lengths`]). The weight
//! `w = s^k` of a side is its piece's free p95 edge strain `s` to the power
//! `k` ([`PatternOptions::negotiation_power`], default 2): the piece that
//! strains more has the less slack, so it has more say (trousers, 20
//! bodies: plain mean `k = 0` leaves 2 of 80 pieces above p95 3 %, worst
//! 3.06 %; `k = 2` none, worst 2.99 %, same mean 2.34 %; the more-strained
//! side alone, 1 of 80 at 3.09 %). Both sides of a seam then have the same
//! length between any two nodes (mismatch and notch mismatch at the solver's
//! tolerance), and the edge strain counts the seams' own stretch like any
//! edge's. (Averaging edge by edge instead gave the same strain to 0.02
//! points on the trousers.) Darts are searched ([`super::darts`]) with the
//! seams free and before the negotiation, so that the seams are negotiated
//! between the darted panels.
//!
//! # Figures (per piece, [`PieceReport`])
//! * area accuracy `E_s = (A − A′)/A` and length accuracy `E_c = (L − L′)/L`
//!   (Wang, Smith & Yuen 2002), edge-length strain `|l′/l − 1|` mean, 95th
//!   percentile and max, flipped triangles ([`super::flatten::distortion`]);
//! * where the strain concentrates: the centroid of the edges above the 95th
//!   percentile and the template node nearest to it — where a dart belongs;
//! * straightness of the waist line (seed 004): the largest distance of the
//!   sew line between the outermost `waist_*` nodes from its chord, mm;
//! * self-intersection of the sew and cut lines.
//!
//! Per seam ([`SeamReport`]): both sides' sew-line lengths, their mismatch,
//! and the notch-distance mismatch; each dart's two legs are reported the
//! same way (they are sewn to each other).
//!
//! **Failure modes** — [`PatternError`], wrapping the stage's error with
//! the panel it concerns.

use std::collections::{BTreeMap, HashSet};

use glam::{DVec2, DVec3};
use rayon::prelude::*;
use serde::{Deserialize, Serialize};
use typed_index_collections::{TiSlice, TiVec};

use super::assemble::{
    assemble, deviation_from_chord, polyline_length, polyline_length_3d, self_intersects, PieceError, PieceOptions,
    PlacedPanel, SeamReport,
};
use super::darts::{dart_opening, insert_darts, AutoDartOptions, DartGuides, DartOrigin, FoundDart, Pass, Trial};
use super::fabric::{fabric_strain, FabricStrain};
use super::flatten::{distortion, flatten_with_sewn_lengths, Distortion, FlattenError, FlattenOptions, Flattening};
use super::grade::{mirror_difference, MirrorDifference};
use super::mirror::{mirror_map, mirrored_flattening};
use super::panels::{cut_plain, CutGarment, Panel, PanelError, PanelVertex, SeamChain};
use super::piece::PatternPiece;
use crate::geom::mesh::{FaceId, VertexId};
use crate::geom::plane::Plane;
use crate::geom::topology::MeshEdge;
use crate::refine::lineage::{node_vertex, vertex_node, Lineage};
use crate::template::format::Template;

/// Knobs of the pattern stage.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct PatternOptions {
    /// Piece assembly (seam allowance, corners, mitres).
    pub piece: PieceOptions,
    /// Flattening.
    pub flatten: FlattenOptions,
    /// A declared dart whose opening on this body is below this, or whose legs
    /// cross (the surface is saddle-shaped there and wants no dart), is left out
    /// and the pattern made again without it; also the least opening of a
    /// dart found by [`super::darts`], mm. Default 3.
    pub min_dart_intake_mm: f64,
    /// Darts added where a piece still strains ([`super::darts`]).
    pub auto_darts: AutoDartOptions,
    /// Hold every seam at its *negotiated* length (module docs) rather than
    /// at its 3D length. Default true.
    pub negotiate_seams: bool,
    /// In the negotiation each side's say is its piece's free p95 edge strain
    /// to this power (module docs; 0: the plain mean of both sides).
    /// Default 2.
    pub negotiation_power: f64,
    /// In a grade run (a size chart, several bodies), decide the darts on
    /// every size afresh rather than once on the base size and carry that
    /// plan to the others ([`DartPlan`]). Default false (issue #14: one
    /// dart plan per grade run; per-size darts differ from size to size,
    /// and a graded nest of them does not stack).
    pub search_every_size: bool,
    /// How far a mirrored dart's vertex may lie from the mirror image of
    /// its pair's ([`Template::mirror_pairs`]), mm. Default 10 (about a
    /// refined edge: the garment on a symmetric mannequin mirrors within
    /// 5–6 mm of a vertex after the depth-map collision; a scan's halves
    /// differ by centimetres, and each side is searched on its own).
    pub mirror_tolerance_mm: f64,
    /// The second panel of a template mirror pair is flattened as the mirror
    /// image of its first ([`super::mirror`]) when the two panels mirror
    /// each other vertex for vertex within this, mm; else on its own.
    /// Default 0.01 (a surface symmetrised by [`crate::refine::symmetry`]
    /// mirrors to rounding, about 10⁻⁹ mm; a scan's halves differ by
    /// centimetres).
    pub mirror_flatten_tolerance_mm: f64,
    /// A template mirror pair is cut as one piece (quantity 2, a cut pair)
    /// when, on the size that decides (a run's base size, or a single
    /// grade), its two pieces' sew lines lie within this of each other after
    /// mirroring ([`crate::pattern::grade::mirror_difference`]), mm. Default
    /// 3 (1/8 in, the tolerance a pattern is checked to: on mirror-symmetric
    /// mannequins the pieces mirror within 0.2 mm once the surface is
    /// symmetrised, [`crate::refine::symmetry`], and within 3 mm without;
    /// a scan's halves differ by centimetres).
    pub cut_pair_line_mm: f64,
    /// … and their areas, widths and heights within this, %. Default 1.
    pub cut_pair_extent_pct: f64,
    /// A piece a template's block gave no found dart holds on another body
    /// ([`DartSource::Block`]) while its p95 edge strain stays under the
    /// search's target or within this of its strain on the block's body
    /// ([`DartPlan::dartless_strain_p95`]), fraction. Default 0.01 (issue
    /// #18: the authored skirt's front, 3.4 % on its design body where no
    /// dart helped it, strains 2.5–3.7 % on the population's bodies, and
    /// held to the target alone every body decided darts of its own; a
    /// fitted bodice's back, under 2.5 % on its block's body, reaches 5.9 %
    /// on a fuller back and still wants darts the block lacks).
    pub block_strain_slack: f64,
}

impl Default for PatternOptions {
    fn default() -> Self {
        Self {
            piece: PieceOptions::default(),
            flatten: FlattenOptions::default(),
            min_dart_intake_mm: 3.0,
            auto_darts: AutoDartOptions::default(),
            negotiate_seams: true,
            negotiation_power: 2.0,
            search_every_size: false,
            mirror_tolerance_mm: 10.0,
            mirror_flatten_tolerance_mm: 0.01,
            cut_pair_line_mm: 3.0,
            cut_pair_extent_pct: 1.0,
            block_strain_slack: 0.01,
        }
    }
}

/// Why the pattern could not be made.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum PatternError {
    /// Cutting into panels failed.
    #[error(transparent)]
    Panel(#[from] PanelError),
    /// Flattening a panel failed.
    #[error("flattening panel '{panel}': {source}")]
    Flatten {
        /// Panel name.
        panel: String,
        /// What went wrong.
        source: FlattenError,
    },
    /// Assembling a piece failed.
    #[error(transparent)]
    Piece(#[from] PieceError),
    /// A dart of the run's plan ([`DartPlan`]) could not be slit into this
    /// size's panel (the plan comes from another refinement of the template).
    #[error("dart '{dart}' of the run's dart plan does not fit panel '{panel}': {reason}")]
    CarriedDart {
        /// Panel name.
        panel: String,
        /// Dart name.
        dart: String,
        /// Why.
        reason: String,
    },
}

/// The darts of a grade run, decided once on its base size and carried to
/// every other size (issue #14, item 1): which declared darts are left out,
/// and the darts found where the base size strained, as chains of the
/// refined mesh's vertex ids. Every size of a template is refined with the
/// same connectivity, so a chain of ids is the same template-relative line
/// on every size: same count, mouths and apexes at the same places.
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize)]
pub struct DartPlan {
    /// Declared darts left out, with their opening on the base size, mm
    /// (negative: inverted) — as [`GarmentPattern::darts_left_out`].
    pub left_out: Vec<(String, f64)>,
    /// Darts found on the base size.
    pub found: Vec<PlannedDart>,
    /// Template mirror pairs cut as one piece (a cut pair) on the base size,
    /// and so on every size of the run: one construction, the same pieces
    /// in every size.
    #[serde(default)]
    pub cut_pairs: Vec<[String; 2]>,
    /// Per piece that got no found dart on the base size, its p95 edge
    /// strain there (fraction): the search found no dart that helped it
    /// ([`PatternOptions::block_strain_slack`]).
    #[serde(default)]
    pub dartless_strain_p95: BTreeMap<String, f64>,
    /// Per seam segment between two template nodes (`[lower, higher]`
    /// node id), its sewn length over its 3D length on the base size, as
    /// negotiated there (module docs, "Negotiated seams"); every other size
    /// of the run sews that segment at its own 3D length times this ratio.
    /// A pattern maker settles a seam's ease once, on the base pattern, and
    /// grades it with the garment: negotiated afresh in each size from that
    /// size's free flattenings, the princess dress's seams took lengths off
    /// the trend of their 3D ones by 4–5 mm (men's chart, size 38) and its
    /// grade points stepped unevenly, 88 of 270 over the bar, against 9 with
    /// every seam at its 3D length (measured). Empty: each size negotiates.
    #[serde(default)]
    pub seam_ratios: Vec<SeamRatio>,
}

/// A seam segment's sewn-to-3D length ratio ([`DartPlan::seam_ratios`]):
/// the segment by its end nodes (`[lower, higher]` template node id).
pub type SeamRatio = ([u32; 2], f64);

/// Where found darts may not run (refined vertex ids; the pipeline's,
/// [`crate::pipeline::grade_with_darts`]).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct DartBarrier {
    /// The template's girth lines ([`crate::pipeline::girth_lines`]): a
    /// dart ends short of the girth it shapes (a waist dart above the hip).
    pub girth_lines: HashSet<VertexId>,
    /// The region that hangs below the garment's lowest girth
    /// ([`crate::pipeline::hanging_vertices`]), opened only to a piece that
    /// cannot meet [`AutoDartOptions::hanging_strain_p95`] with it closed.
    pub hanging: HashSet<VertexId>,
}

/// How a template mirror pair came out ([`Template::mirror_pairs`]).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct CutPair {
    /// The two panels, as the template pairs them.
    pub panels: [String; 2],
    /// The piece that stands for both where they are cut as a pair
    /// (`front` for `left_front`/`right_front`).
    pub piece: String,
    /// Whether they are cut as one piece (quantity 2); otherwise both stay,
    /// each cut once (a scan's halves differ).
    pub cut_as_pair: bool,
    /// How far the second is from the mirror image of the first.
    pub difference: MirrorDifference,
}

/// A found dart of a [`DartPlan`].
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct PlannedDart {
    /// The panel it is slit into.
    pub panel: String,
    /// Its name (`dart_auto_<panel>_<k>`).
    pub name: String,
    /// Its line, refined-mesh vertices from the mouth on the outline to the apex.
    pub chain: Vec<VertexId>,
}

/// Where the strain of a piece concentrates.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, utoipa::ToSchema)]
pub struct StrainHotspot {
    /// Centroid of the edges above the 95th percentile, piece coordinates, mm.
    #[schema(value_type = Vec<f64>, min_items = 2, max_items = 2)]
    pub at: DVec2,
    /// The template node nearest to it (its feature point, e.g. `bust_front_left`).
    pub near: String,
    /// Its distance from that node, mm.
    pub distance_mm: f64,
}

/// Figures of one piece.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, utoipa::ToSchema)]
pub struct PieceReport {
    /// Piece name.
    pub name: String,
    /// Size.
    pub size: String,
    /// Distortion of the flattening.
    pub distortion: Distortion,
    /// Thread strain and weave shear of the piece as cut from woven cloth
    /// (warp along the grain line; [`super::fabric`]).
    pub fabric: FabricStrain,
    /// ARAP iterations done.
    pub iterations: usize,
    /// Whether ARAP met its tolerance.
    pub converged: bool,
    /// Whether ARAP flipped triangles and the LSCM map was used instead.
    pub fallback: bool,
    /// Surface area of the panel, mm².
    pub area_3d_mm2: f64,
    /// Where the strain concentrates.
    pub hotspot: Option<StrainHotspot>,
    /// Waist-line straightness, mm (`None` when the piece has no waist line).
    pub waist_deviation_mm: Option<f64>,
    /// Whether the sew line crosses itself.
    pub sew_line_self_intersects: bool,
    /// Whether the cut line crosses itself.
    pub cut_line_self_intersects: bool,
    /// Darts added where the piece strained ([`super::darts`]), in the order
    /// found, or carried from the run's base size, or mirrored from the
    /// piece's mirror pair ([`FoundDart::origin`]); at most
    /// [`AutoDartOptions::max_darts`]; empty when the declared darts sufficed.
    pub found_darts: Vec<FoundDart>,
}

/// The pattern of one garment in one size.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct GarmentPattern {
    /// Garment (template) name.
    pub style: String,
    /// Size.
    pub size: String,
    /// Pieces in template panel order.
    pub pieces: Vec<PatternPiece>,
    /// Per piece, same order.
    pub reports: Vec<PieceReport>,
    /// Per seam, template order (then the darts' legs).
    pub seams: Vec<SeamReport>,
    /// Declared darts left out on this body (no intake, or inverted), with their
    /// opening when they were tried, mm (negative: inverted).
    pub darts_left_out: Vec<(String, f64)>,
    /// The dart plan this pattern was made with: found here (a base size,
    /// a single grade), or carried from the run's base size.
    #[serde(default)]
    pub dart_plan: DartPlan,
    /// Every template mirror pair: cut as one piece or kept apart, and by
    /// how much its two pieces differ.
    #[serde(default)]
    pub cut_pairs: Vec<CutPair>,
}

/// The pattern of the fine mesh (`positions` in metres, `triangles`) that
/// the refinement made of template `t`, with its `lineage` (module docs), its
/// darts decided here ([`pattern_with_plan`] without a plan).
///
/// # Errors
/// [`PatternError`].
pub fn pattern(
    t: &Template,
    positions: &TiSlice<VertexId, DVec3>,
    triangles: &TiSlice<FaceId, [VertexId; 3]>,
    lineage: &Lineage,
    size: &str,
    opts: &PatternOptions,
) -> Result<GarmentPattern, PatternError> {
    pattern_with_plan(t, positions, triangles, lineage, size, opts, None)
}

/// [`pattern`] with the darts of `plan` when given (a size of a run whose
/// base size decided them: the declared darts it leaves out are left out,
/// its found darts are slit along the same vertex chains, and nothing is
/// searched), else decided on this mesh: every declared dart that opens is
/// kept (one that does not goes with its mirror image, `…_left` ↔
/// `…_right`), and, with [`AutoDartOptions::enabled`], darts are searched where a
/// piece still strains. The result's [`GarmentPattern::dart_plan`] is the
/// plan used.
///
/// # Errors
/// [`PatternError`]; [`PatternError::CarriedDart`] when a planned chain is
/// not a line of this mesh's panel.
pub fn pattern_with_plan(
    t: &Template,
    positions: &TiSlice<VertexId, DVec3>,
    triangles: &TiSlice<FaceId, [VertexId; 3]>,
    lineage: &Lineage,
    size: &str,
    opts: &PatternOptions,
    plan: Option<&DartPlan>,
) -> Result<GarmentPattern, PatternError> {
    pattern_with_darts(t, positions, triangles, lineage, size, opts, DartSource::from(plan), &DartBarrier::default())
}

/// Where the darts of a pattern come from.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum DartSource<'a> {
    /// Decided on this body: every declared dart that opens is kept, and
    /// darts are searched where a piece still strains ([`pattern_with_plan`]
    /// without a plan).
    Decide,
    /// A grade run's plan, decided on its base size, carried as it is: the
    /// same darts, the same cut pairs and the same seam ratios
    /// ([`DartPlan::seam_ratios`]) in every size of the run.
    Run(&'a DartPlan),
    /// The template's *block*: its plan on the body it was designed on
    /// (issue #15; made-to-measure as a pattern maker drafts it: the
    /// customer's pattern is the style's block altered, its darts where
    /// the block has them, each opening by what this body needs). Carried
    /// where it holds on this body — every dart opens by at least
    /// [`PatternOptions::min_dart_intake_mm`] with legs that do not cross,
    /// no piece folds, no sew or cut line crosses itself, no line is left
    /// unclean, and no piece the block gives no dart strains past
    /// [`AutoDartOptions::target_strain_p95`] (it wants darts the block
    /// lacks) — else decided here as by [`DartSource::Decide`]. Mirror
    /// pairs are paired on this body either way (a scan's halves differ).
    Block(&'a DartPlan),
}

impl<'a> From<Option<&'a DartPlan>> for DartSource<'a> {
    /// A run's plan where given, else [`DartSource::Decide`].
    fn from(plan: Option<&'a DartPlan>) -> Self {
        plan.map_or(DartSource::Decide, DartSource::Run)
    }
}

/// [`pattern_with_plan`] with its darts from `source` ([`DartSource`]),
/// found darts kept out of `barrier` ([`DartBarrier`]; [`pattern`] and
/// [`pattern_with_plan`] give none). The result's [`GarmentPattern::dart_plan`] is the plan used; with
/// a block that did not hold, the one decided here.
///
/// # Errors
/// [`PatternError`]; [`PatternError::CarriedDart`] when a run's planned
/// chain is not a line of this mesh's panel (a block's falls back to
/// deciding here).
#[expect(
    clippy::too_many_arguments,
    reason = "the refined garment, its size, the options, where its darts come from and where they may not run"
)]
pub fn pattern_with_darts(
    t: &Template,
    positions: &TiSlice<VertexId, DVec3>,
    triangles: &TiSlice<FaceId, [VertexId; 3]>,
    lineage: &Lineage,
    size: &str,
    opts: &PatternOptions,
    source: DartSource<'_>,
    barrier: &DartBarrier,
) -> Result<GarmentPattern, PatternError> {
    let (mut g, decided) = match source {
        DartSource::Decide => (pattern_darts(t, positions, triangles, lineage, size, opts, barrier)?, None),
        DartSource::Run(plan) => {
            (carry_plan(t, positions, triangles, lineage, size, opts, plan)?.0, Some(plan.cut_pairs.as_slice()))
        }
        DartSource::Block(plan) => {
            // a block carries its darts to another figure, not its seams' ease: each body's seams
            // are negotiated on it (the reference body's ratios carried to the population strained
            // the helper skirt's back 4.67 % p95 on pop28, over its 4.6 % ceiling; measured)
            let own_seams = DartPlan { seam_ratios: Vec::new(), ..plan.clone() };
            let carried = carry_plan(t, positions, triangles, lineage, size, opts, &own_seams).ok();
            let g = match carried.filter(|(g, checks)| block_holds(g, checks, plan, opts)) {
                Some((g, _)) => g,
                None => pattern_darts(t, positions, triangles, lineage, size, opts, barrier)?,
            };
            (g, None)
        }
    };
    pair_pieces(t, &mut g, decided, opts);
    Ok(g)
}

/// Whether a pattern made with carried darts holds (module docs of
/// [`DartSource::Block`]): every dart (declared or carried) opens by at
/// least [`PatternOptions::min_dart_intake_mm`], no piece folds, no sew or
/// cut line crosses itself, and no internal line is left unclean.
fn block_holds(g: &GarmentPattern, checks: &[DartCheck], plan: &DartPlan, opts: &PatternOptions) -> bool {
    let opens = checks.iter().all(|(_, opening, crossing)| !crossing && *opening >= opts.min_dart_intake_mm);
    let unfolded = g
        .reports
        .iter()
        .all(|r| r.distortion.flipped == 0 && !r.sew_line_self_intersects && !r.cut_line_self_intersects);
    // a piece the block gave no dart (its reference body's piece needed none) that strains here
    // past the search's target wants darts the block lacks (a fitted bodice's back on a fuller
    // back: 3.0 % p95 with its own darts, 5.9 % with none), unless it strains about as much as
    // it did on the block's body, where no dart helped it
    let dartless_fit = g.reports.iter().all(|r| {
        let reference = plan.dartless_strain_p95.get(&r.name).map_or(0.0, |s| s + opts.block_strain_slack);
        !r.found_darts.is_empty()
            || !opts.auto_darts.enabled
            || r.distortion.strain_p95 <= opts.auto_darts.target_strain_p95.max(reference)
    });
    opens && unfolded && dartless_fit && g.pieces.iter().all(|p| super::lines::line_problems(p).is_empty())
}

/// The pieces of every template mirror pair: cut as one (the first panel's
/// piece named for both, quantity summed, [`PatternPiece::cut_pair`]) where
/// `decided` lists the pair or, without a run's decision, where the two
/// mirror within [`PatternOptions::cut_pair_line_mm`] and
/// [`PatternOptions::cut_pair_extent_pct`]; the decision joins the
/// pattern's plan, and every pair is reported with its difference.
fn pair_pieces(t: &Template, g: &mut GarmentPattern, decided: Option<&[[String; 2]]>, opts: &PatternOptions) {
    for [a, b] in &t.mirror_pairs {
        let (Some(ia), Some(ib)) =
            (g.pieces.iter().position(|p| p.name == *a), g.pieces.iter().position(|p| p.name == *b))
        else {
            continue;
        };
        let difference = mirror_difference(&g.pieces[ia], &g.pieces[ib]);
        let pair = [a.clone(), b.clone()];
        let cut_as_pair = match decided {
            Some(list) => list.contains(&pair),
            None => {
                let extent = difference.area_pct.max(difference.width_pct).max(difference.height_pct);
                difference.sew_line_mm <= opts.cut_pair_line_mm && extent <= opts.cut_pair_extent_pct
            }
        };
        let piece = if cut_as_pair { pair_name(a, b) } else { a.clone() };
        if cut_as_pair {
            let quantity = g.pieces[ib].quantity;
            let first = &mut g.pieces[ia];
            first.name = piece.clone();
            first.quantity += quantity;
            first.cut_pair = true;
            g.pieces.remove(ib);
            g.dart_plan.cut_pairs.push(pair.clone());
        }
        g.cut_pairs.push(CutPair { panels: pair, piece, cut_as_pair, difference });
    }
}

/// The name of the piece that stands for a mirror pair: the two panel names
/// without their side (`left_front`, `right_front` → `front`;
/// `sleeve_left`, `sleeve_right` → `sleeve`), else the first name.
fn pair_name(a: &str, b: &str) -> String {
    let prefixed = a.strip_prefix("left_").zip(b.strip_prefix("right_"));
    let suffixed = a.strip_suffix("_left").zip(b.strip_suffix("_right"));
    match prefixed.or(suffixed) {
        Some((x, y)) if x == y && !x.is_empty() => x.to_owned(),
        _ => a.to_owned(),
    }
}

/// [`pattern_with_darts`] before the mirror pairs are paired, its darts
/// decided on this mesh ([`DartSource::Decide`]; a plan is carried by
/// [`carry_plan`]).
fn pattern_darts(
    t: &Template,
    positions: &TiSlice<VertexId, DVec3>,
    triangles: &TiSlice<FaceId, [VertexId; 3]>,
    lineage: &Lineage,
    size: &str,
    opts: &PatternOptions,
    barrier: &DartBarrier,
) -> Result<GarmentPattern, PatternError> {
    // cut once: each pass below slits its darts into copies of these panels
    let plain = cut_plain(t, positions, triangles, lineage)?;
    let mut tt = t.clone();
    let mut left_out = Vec::new();
    loop {
        let (mut g, darts) = pattern_once(&tt, positions, &plain, lineage, size, opts, Search::None)?;
        // the worst dart that does not open (or opens inverted) goes, and the pattern is made again
        let worst = darts
            .iter()
            .filter(|(_, opening, crossing)| *crossing || *opening < opts.min_dart_intake_mm)
            .min_by(|a, b| a.1.total_cmp(&b.1))
            .cloned();
        match worst {
            Some((name, opening, _)) => {
                // and its mirror image (`…_left` ↔ `…_right`): a pattern maker keeps darts in pairs
                let mirror = mirror_name(&name).filter(|m| *m != name && tt.darts.iter().any(|d| d.name == *m));
                tt.darts.retain(|d| d.name != name && Some(&d.name) != mirror.as_ref());
                left_out.push((name, opening));
                if let Some(m) = mirror {
                    let o = darts.iter().find(|d| d.0 == m).map_or(0.0, |d| d.1);
                    left_out.push((m, o));
                }
            }
            None => {
                // the declared darts are settled: darts where a piece still strains
                let target = opts.auto_darts.target_strain_p95;
                if opts.auto_darts.enabled && g.reports.iter().any(|r| r.distortion.strain_p95 > target) {
                    g = pattern_once(&tt, positions, &plain, lineage, size, opts, Search::Find(barrier))?.0;
                }
                g.dart_plan.left_out = left_out.clone();
                g.darts_left_out = left_out;
                return Ok(g);
            }
        }
    }
}

/// [`pattern_darts`] with `plan`'s darts carried: the declared darts it
/// leaves out are left out, its found darts slit along the same chains;
/// with every dart's opening and whether its piece's sew line crosses
/// itself.
fn carry_plan(
    t: &Template,
    positions: &TiSlice<VertexId, DVec3>,
    triangles: &TiSlice<FaceId, [VertexId; 3]>,
    lineage: &Lineage,
    size: &str,
    opts: &PatternOptions,
    plan: &DartPlan,
) -> Result<(GarmentPattern, Vec<DartCheck>), PatternError> {
    let plain = cut_plain(t, positions, triangles, lineage)?;
    let mut tt = t.clone();
    tt.darts.retain(|d| !plan.left_out.iter().any(|(name, _)| *name == d.name));
    let (mut g, checks) = pattern_once(&tt, positions, &plain, lineage, size, opts, Search::Carry(plan))?;
    g.darts_left_out = plan.left_out.clone();
    g.dart_plan.left_out = plan.left_out.clone();
    g.dart_plan.dartless_strain_p95 = plan.dartless_strain_p95.clone();
    Ok((g, checks))
}

/// The name of the mirror image of a left or right dart (`dart_front_left`
/// ↔ `dart_front_right`); `None` for a name with neither.
fn mirror_name(name: &str) -> Option<String> {
    if name.contains("left") {
        Some(name.replacen("left", "right", 1))
    } else if name.contains("right") {
        Some(name.replacen("right", "left", 1))
    } else {
        None
    }
}

/// Where [`pattern_once`]'s extra darts come from.
#[derive(Clone, Copy)]
enum Search<'a> {
    /// None: the declared darts only.
    None,
    /// Searched where a piece strains ([`search_darts`]), kept out of the
    /// barrier given.
    Find(&'a DartBarrier),
    /// Carried from a plan (its found darts and its seam ratios).
    Carry(&'a DartPlan),
}

/// Slits the planned darts of `panel` (global vertex chains mapped to its local ids).
fn carry_darts(panel: &mut Panel, planned: &[PlannedDart]) -> Result<Vec<FoundDart>, PatternError> {
    let mut found = Vec::new();
    let name = panel.name.clone();
    for d in planned.iter().filter(|d| d.panel == name) {
        let err = |reason: String| PatternError::CarriedDart { panel: name.clone(), dart: d.name.clone(), reason };
        let chain: Vec<PanelVertex> = d
            .chain
            .iter()
            .map(|&g| panel.local(g).ok_or_else(|| err(format!("vertex {g} is not in the panel"))))
            .collect::<Result<_, _>>()?;
        panel.add_dart(&d.name, &chain).map_err(err)?;
        let pts: Vec<DVec3> = chain.iter().map(|&l| panel.positions[l]).collect();
        found.push(FoundDart {
            name: d.name.clone(),
            length_mm: polyline_length_3d(&pts) * 1e3,
            intake_mm: 0.0,
            strain_p95_before: 0.0,
            strain_p95_after: 0.0,
            apex: pts.last().copied().unwrap_or_default(),
            origin: DartOrigin::Carried,
        });
    }
    Ok(found)
}

/// A dart's name, signed opening (mm, negative when inverted) and whether its
/// piece's sew line crosses itself.
type DartCheck = (String, f64, bool);

/// Sewn-length ratio `ℓ′/ℓ` of every seam edge of every panel, keyed by the
/// panel's index and the edge of the refined mesh (module docs,
/// *Negotiated seams*).
type SewnRatios = BTreeMap<(usize, MeshEdge), f64>;

/// This panel's seams (and darts) as chains of local ids, for
/// [`flatten_with_sewn_lengths`] to hold at their sewn lengths so both sides
/// agree, with each chain edge's ratio from `sewn` (1 where it has none:
/// the 3D length; always for dart legs). With `hold_seams` off only the
/// dart legs are held (plus a one-vertex chain, which holds nothing, so
/// that the seams are free rather than all held).
fn seam_chains(panel: &Panel, seams: &[SeamChain], sewn: &SewnRatios, hold_seams: bool) -> SeamHolds {
    let runs: Vec<Vec<PanelVertex>> = if hold_seams {
        seam_runs(panel, seams)
    } else {
        panel.outline.first().map(|&v| vec![v]).into_iter().collect()
    };
    let ratios = runs
        .iter()
        .map(|run| {
            run.windows(2)
                .map(|w| {
                    let edge = MeshEdge::new(panel.global[w[0]], panel.global[w[1]]);
                    sewn.get(&(panel.index, edge)).copied().unwrap_or(1.0)
                })
                .collect()
        })
        .collect();
    let darts = panel.darts.iter().flat_map(|d| [d.a.clone(), d.b.clone()]);
    SeamHolds { chains: runs.into_iter().chain(darts).collect(), ratios }
}

/// The runs of `panel`'s outline along its seams (local ids; a seam through
/// a dart mouth runs in two pieces).
fn seam_runs(panel: &Panel, seams: &[SeamChain]) -> Vec<Vec<PanelVertex>> {
    seams
        .iter()
        .filter(|s| s.panel_a == panel.index || s.panel_b == panel.index)
        .filter_map(|s| panel.seam_runs(&s.chain))
        .flatten()
        .collect()
}

/// Chains of local ids a panel's flattening holds, and the sewn-length
/// ratios of the first ones' edges ([`flatten_with_sewn_lengths`]).
struct SeamHolds {
    chains: Vec<Vec<PanelVertex>>,
    ratios: Vec<Vec<f64>>,
}

/// Flattens `panel` with `holds` ([`seam_chains`]).
fn flatten_held(panel: &Panel, holds: &SeamHolds, opts: &FlattenOptions) -> Result<Flattening, FlattenError> {
    flatten_with_sewn_lengths(&panel.positions, &panel.triangles, &holds.chains, &holds.ratios, opts)
}

/// The error of a failed flattening of `panel`.
fn flatten_error(panel: &Panel) -> impl FnOnce(FlattenError) -> PatternError {
    let name = panel.name.clone();
    move |source| PatternError::Flatten { panel: name, source }
}

/// Negotiated seam lengths (module docs): every panel flattened with its
/// seams free; along each seam, between consecutive template nodes (where
/// notches sit), both sides are held at the mean of the lengths they took,
/// each edge scaled from its own free length.
fn negotiate(
    panels: &[Panel],
    free: &[Trial],
    seams: &[SeamChain],
    n_nodes: usize,
    power: f64,
    carried: &[SeamRatio],
) -> (SewnRatios, Vec<SeamRatio>) {
    let carried: BTreeMap<[u32; 2], f64> = carried.iter().copied().collect();
    let mut ratios = Vec::new();
    // a side without strain has no say of its own (nor does any side when none strains)
    let say: Vec<f64> =
        free.iter().map(|f| if power == 0.0 { 1.0 } else { f.distortion.strain_p95.max(0.0).powf(power) }).collect();
    let flats: Vec<&Flattening> = free.iter().map(|f| &f.flat).collect();
    let mut sewn = SewnRatios::new();
    for s in seams.iter().filter(|s| s.panel_a != s.panel_b) {
        let sides = [s.panel_a, s.panel_b];
        let weights = sides.map(|p| say[p]);
        let total: f64 = weights.iter().sum();
        let Some(edges) = sides.iter().map(|&p| panels[p].seam_edges(&s.chain)).collect::<Option<Vec<_>>>() else {
            continue;
        };
        // per side and chain edge: 3D and free 2D length
        let lengths: Vec<Vec<(f64, f64)>> = sides
            .iter()
            .zip(&edges)
            .map(|(&p, edges)| {
                edges
                    .iter()
                    .map(|&[u, w]| {
                        let l3 = panels[p].positions[u].distance(panels[p].positions[w]);
                        let l2 = flats[p].uv[u].distance(flats[p].uv[w]);
                        (l3, if l2 > 0.0 { l2 } else { l3 })
                    })
                    .collect()
            })
            .collect();
        let mut start = 0;
        for end in 1..s.chain.len() {
            if vertex_node(s.chain[end], n_nodes).is_none() && end + 1 < s.chain.len() {
                continue;
            }
            let free: Vec<f64> = lengths.iter().map(|l| l[start..end].iter().map(|e| e.1).sum()).collect();
            // the segment by its end nodes, and its 3D length (one chain: both sides alike)
            let key = match (vertex_node(s.chain[start], n_nodes), vertex_node(s.chain[end], n_nodes)) {
                (Some(a), Some(b)) => Some([a.min(b), a.max(b)]),
                _ => None,
            };
            let l3: f64 = lengths[0][start..end].iter().map(|e| e.0).sum();
            let carried_ratio = key.and_then(|k| carried.get(&k)).copied();
            let held = match carried_ratio {
                Some(ratio) => l3 * ratio,
                None if total > 0.0 && total.is_finite() => {
                    free.iter().zip(&weights).map(|(f, w)| f * w).sum::<f64>() / total
                }
                None => free.iter().sum::<f64>() / free.len() as f64,
            };
            if let Some(k) = key.filter(|_| l3 > 0.0) {
                // the run's ratio as carried, bit for bit (the plan is the same in every size)
                ratios.push((k, carried_ratio.unwrap_or(held / l3)));
            }
            for ((&p, edges), (l, f)) in sides.iter().zip(&edges).zip(lengths.iter().zip(&free)) {
                for k in start..end {
                    let (l3, l2) = l[k];
                    if l3 > 0.0 && *f > 0.0 {
                        let [u, w] = edges[k].map(|v| panels[p].global[v]);
                        sewn.insert((p, MeshEdge::new(u, w)), l2 * held / f / l3);
                    }
                }
            }
            start = end;
        }
    }
    (sewn, ratios)
}

/// `panel` flattened with its seams free (dart legs held), and how it strains.
fn flatten_free(panel: &Panel, seams: &[SeamChain], opts: &FlattenOptions) -> Result<Trial, PatternError> {
    let flat = flatten_held(panel, &seam_chains(panel, seams, &SewnRatios::new(), false), opts)
        .map_err(flatten_error(panel))?;
    Ok(Trial { distortion: distortion(&panel.positions, &panel.triangles, &flat.uv), flat })
}

/// One pass of [`pattern`] with every declared dart (and, with `find_darts`,
/// darts found where a piece strains); also each declared dart's signed
/// opening (mm, negative when inverted) and whether its piece's sew line crosses itself.
///
/// Its steps, each a function with a typed result (issue #16, item 3): the
/// declared darts slit into the garment cut once by the caller
/// ([`CutGarment::darted`]) → the pass's found or carried darts
/// ([`pass_darts`] → [`PassDarts`]) → the seams' sewn lengths
/// ([`sewn_lengths`]) → every panel flattened with them, side by side →
/// the pieces assembled ([`assemble`]) → their figures ([`piece_report`]).
/// A found dart that leaves its piece folded or its lines unclean lowers
/// its panel's cap, and the steps from the darts on run again (searches
/// whose cap did not change are reused).
fn pattern_once(
    t: &Template,
    positions: &TiSlice<VertexId, DVec3>,
    plain: &CutGarment,
    lineage: &Lineage,
    size: &str,
    opts: &PatternOptions,
    search: Search<'_>,
) -> Result<(GarmentPattern, Vec<DartCheck>), PatternError> {
    let find_darts = matches!(search, Search::Find(_));
    let cut_panels = plain.darted(t, positions, lineage)?;
    let seams = &plain.seams;
    let n_nodes = t.nodes.len();
    // darts where a piece strains, searched with the seams free when they are negotiated afterwards;
    // per panel at most `cap` of them, lowered when the negotiated flattening of the darted panel
    // folds or crosses its sew line (the search saw the free one)
    let mut cap = vec![opts.auto_darts.max_darts; cut_panels.len()];
    // per panel: the cap searched with, the darted panel, its darts and its search flattening
    let mut searched: Vec<Option<(usize, Searched)>> = vec![None; cut_panels.len()];
    // the second panel of a mirror pair takes the first's darts, mirrored (issue #14)
    let empty = DartBarrier::default();
    let barrier = match search {
        Search::Find(barrier) => barrier,
        _ => &empty,
    };
    let plane = mirror_plane(t, positions);
    let second_of: Vec<Option<usize>> = cut_panels
        .iter()
        .map(|p| {
            let [a, _] = t.mirror_pairs.iter().find(|[_, b]| *b == p.name)?;
            cut_panels.iter().position(|q| q.name == *a)
        })
        .collect();
    loop {
        // step: this pass's darts (declared, and found or carried)
        let PassDarts { panels, found_darts, free } = pass_darts(
            t,
            positions,
            &cut_panels,
            seams,
            opts,
            search,
            &cap,
            &mut searched,
            (&second_of, plane),
            barrier,
        )?;
        // step: the seams' sewn lengths, negotiated between their sides
        let carried: &[SeamRatio] = match search {
            Search::Carry(plan) => &plan.seam_ratios,
            _ => &[],
        };
        let (sewn, seam_ratios) =
            sewn_lengths(&panels, free, seams, n_nodes, opts, find_darts, (&second_of, plane), carried)?;
        let mut pieces = Vec::with_capacity(panels.len());
        let mut placed = Vec::with_capacity(panels.len());
        let mut reports = Vec::with_capacity(panels.len());
        let mut refused = false;
        // the panels' flattenings with the negotiated seams, side by side; a mirror pair's second
        // panel the mirror image of its first's
        let flats = flatten_pairs(
            &panels,
            (&second_of, plane),
            opts,
            |panel| {
                let holds = seam_chains(panel, seams, &sewn, true);
                flatten_held(panel, &holds, &opts.flatten).map_err(flatten_error(panel))
            },
            mirrored_flattening,
        );
        for (i, ((panel, found_darts), flat)) in panels.iter().zip(found_darts).zip(flats).enumerate() {
            let flat = flat?;
            let d = distortion(&panel.positions, &panel.triangles, &flat.uv);
            let p = assemble(t, panel, seams, lineage, &flat.uv, size, &opts.piece)?;
            let sew_line_self_intersects = self_intersects(&p.piece.sew_line);
            let cut_line_self_intersects = self_intersects(&p.piece.cut_line);
            // found darts that leave a line of the piece unclean (issue #14, item 5: legs that cross
            // near a concave mouth once the seams are negotiated; a girth line pushed out of the
            // piece by a dart's mouth) are refused too
            let unclean = || !super::lines::line_problems(&p.piece).is_empty();
            // with guided darts, so are found darts that do not open by the least intake in the
            // piece as cut (the search saw them open with the seams free: the authored skirt's
            // second back pair opened 5.1 mm there and 1.9 mm once the seams were negotiated, and
            // a block with it did not hold on the next body)
            let shut = || {
                let rim = panel.rim();
                opts.auto_darts.guided
                    && found_darts.iter().filter_map(|f| panel.darts.iter().find(|l| l.name == f.name)).any(|legs| {
                        dart_opening(&rim, &flat.uv, legs).is_none_or(|o| o * 1e3 < opts.min_dart_intake_mm)
                    })
            };
            if find_darts
                && !found_darts.is_empty()
                && (d.flipped > 0 || sew_line_self_intersects || cut_line_self_intersects || unclean() || shut())
            {
                // the last round's darts fewer: a mirrored pair on a piece that is its own mirror
                // image is two darts found in one round (a cap one lower would find the same pair
                // again); a mirror pair's second panel's darts are all mirrored, one a round
                let own = found_darts.iter().filter(|f| f.origin == DartOrigin::Found).count();
                let last_round =
                    if own > 0 && found_darts.last().is_some_and(|f| f.origin == DartOrigin::Mirrored) { 2 } else { 1 };
                cap[i] = found_darts.len().saturating_sub(last_round);
                // a mirrored panel's darts are its pair's: the pair gives one up
                if let Some(j) = second_of[i] {
                    cap[j] = cap[j].min(cap[i]);
                }
                refused = true;
            }
            reports.push(piece_report(
                t,
                panel,
                &flat,
                &p,
                d,
                size,
                found_darts,
                [sew_line_self_intersects, cut_line_self_intersects],
            ));
            pieces.push(p.piece.clone());
            placed.push(p);
        }
        if !refused {
            // the found (or carried) darts as lines of the refined mesh: the run's plan
            let found: Vec<PlannedDart> = panels
                .iter()
                .zip(&reports)
                .flat_map(|(panel, r)| {
                    r.found_darts.iter().filter_map(|f| {
                        let legs = panel.darts.iter().find(|d| d.name == f.name)?;
                        Some(PlannedDart {
                            panel: panel.name.clone(),
                            name: f.name.clone(),
                            chain: legs.a.iter().map(|&l| panel.global[l]).collect(),
                        })
                    })
                })
                .collect();
            let (mut g, checks) = finish(t, positions, size, panels, seams, pieces, placed, reports);
            g.dart_plan.found = found;
            g.dart_plan.seam_ratios = seam_ratios;
            g.dart_plan.dartless_strain_p95 = g
                .reports
                .iter()
                .filter(|r| r.found_darts.is_empty())
                .map(|r| (r.name.clone(), r.distortion.strain_p95))
                .collect();
            if let Search::Carry(_) = search {
                // a carried dart opens by what this size's flattening gives it; nothing was searched
                for r in &mut g.reports {
                    let p95 = r.distortion.strain_p95;
                    for f in &mut r.found_darts {
                        f.intake_mm = checks.iter().find(|c| c.0 == f.name).map_or(0.0, |c| c.1);
                        (f.strain_p95_before, f.strain_p95_after) = (p95, p95);
                    }
                }
            }
            return Ok((g, checks));
        }
    }
}

/// The darts of one pass of [`pattern_once`]: the panels with the declared
/// darts slit (as cut) and the found or carried ones, the found darts per
/// panel, and, where the search ran, each panel's free flattening.
struct PassDarts {
    panels: Vec<Panel>,
    found_darts: Vec<Vec<FoundDart>>,
    free: Vec<Option<Trial>>,
}

/// The dart step of a pass: with [`Search::Find`], darts searched where a
/// piece strains (at most `cap[i]` per panel, searches reused from
/// `searched` when their cap is unchanged; a mirror pair's second panel
/// takes its first's darts mirrored, `second_of`); with [`Search::Carry`],
/// the plan's darts slit along the same chains.
#[expect(clippy::too_many_arguments, reason = "one step of a pass: its inputs and the pass's search state")]
fn pass_darts(
    t: &Template,
    positions: &TiSlice<VertexId, DVec3>,
    cut_panels: &[Panel],
    seams: &[SeamChain],
    opts: &PatternOptions,
    search: Search<'_>,
    cap: &[usize],
    searched: &mut [Option<(usize, Searched)>],
    (second_of, plane): Pairs<'_>,
    barrier: &DartBarrier,
) -> Result<PassDarts, PatternError> {
    let find_darts = matches!(search, Search::Find(_));
    let n_nodes = t.nodes.len();
    let mut panels = cut_panels.to_vec();
    let mut found_darts = vec![Vec::new(); panels.len()];
    // with negotiated seams, the search's last flattening is the free one the negotiation needs
    let mut free: Vec<Option<Trial>> = vec![None; panels.len()];
    if find_darts {
        // the panels' searches are independent: side by side on rayon's pool (issue #15),
        // the first failure in panel order reported
        let fresh: Vec<(usize, Result<Searched, PatternError>)> = (0..panels.len())
            .filter(|&i| second_of[i].is_none() && searched[i].as_ref().is_none_or(|(c, _)| *c != cap[i]))
            .collect::<Vec<_>>()
            .into_par_iter()
            .map(|i| {
                let options = AutoDartOptions { max_darts: cap[i], ..opts.auto_darts };
                let guides = dart_guides(t, positions, &panels[i], plane, barrier, opts);
                (i, search_darts(&panels[i], seams, n_nodes, opts, &options, &guides))
            })
            .collect();
        for (i, found) in fresh {
            searched[i] = Some((cap[i], found?));
        }
        for (i, panel) in panels.iter_mut().enumerate() {
            if second_of[i].is_some() {
                continue;
            }
            let Some((_, found)) = searched[i].clone() else { continue };
            (*panel, found_darts[i], free[i]) = (found.panel, found.darts, Some(found.last));
        }
        let seconds: Vec<(usize, Result<Searched, PatternError>)> = (0..panels.len())
            .filter_map(|i| Some((i, second_of[i]?)))
            .collect::<Vec<_>>()
            .into_par_iter()
            .map(|(i, first)| {
                let mut panel = panels[i].clone();
                let mirrored = plane.and_then(|plane| {
                    mirror_darts(&panels[first], &found_darts[first], &mut panel, positions, plane, opts)
                });
                let done = match mirrored {
                    Some(darts) => {
                        // the first's free flattening, mirrored, where the darted panels mirror exactly
                        let last = match (pair_map(&panels[first], &panel, plane, opts), &free[first]) {
                            (Some(map), Some(trial)) => Ok(mirrored_trial(trial, &map)),
                            _ => flatten_free(&panel, seams, &opts.flatten),
                        };
                        last.map(|last| Searched { panel, darts, last })
                    }
                    None => {
                        // not a mirror image here (a scan): searched on its own
                        let options = AutoDartOptions { max_darts: cap[i], ..opts.auto_darts };
                        let guides = dart_guides(t, positions, &panels[i], None, barrier, opts);
                        search_darts(&panels[i], seams, n_nodes, opts, &options, &guides)
                    }
                };
                (i, done)
            })
            .collect();
        for (i, done) in seconds {
            let found = done?;
            (panels[i], found_darts[i], free[i]) = (found.panel, found.darts, Some(found.last));
        }
    }
    if let Search::Carry(DartPlan { found: planned, .. }) = search {
        for (i, panel) in panels.iter_mut().enumerate() {
            found_darts[i] = carry_darts(panel, planned)?;
        }
    }
    Ok(PassDarts { panels, found_darts, free })
}

/// The template's mirror pairs among a pass's panels: per panel, the panel
/// whose second it is (`None`: not a pair's second panel); and the body's
/// mirror plane `n·p = d`, where it has one ([`mirror_plane`]).
type Pairs<'a> = (&'a [Option<usize>], Option<(DVec3, f64)>);

/// The vertex map of `second` onto `first`, a template mirror pair's
/// panels, where they mirror across `plane` within
/// [`PatternOptions::mirror_flatten_tolerance_mm`] ([`mirror_map`]).
fn pair_map(
    first: &Panel,
    second: &Panel,
    plane: Option<(DVec3, f64)>,
    opts: &PatternOptions,
) -> Option<TiVec<PanelVertex, PanelVertex>> {
    mirror_map(first, second, plane?, opts.mirror_flatten_tolerance_mm * 1e-3)
}

/// A mirror pair's first panel's flattening and distortion as its second's
/// ([`mirrored_flattening`]: the distortion of a mirror image is the same).
fn mirrored_trial(first: &Trial, map: &TiVec<PanelVertex, PanelVertex>) -> Trial {
    Trial { flat: mirrored_flattening(&first.flat, map), distortion: first.distortion }
}

/// Every panel's flattening by `flat`, side by side; the second panel of a
/// mirror pair its first's, mirrored by `mirror`, where the two panels
/// mirror ([`pair_map`]), else its own (also where its first's failed: the
/// pattern fails on the first, in panel order).
fn flatten_pairs<T, F, M>(
    panels: &[Panel],
    (second_of, plane): Pairs<'_>,
    opts: &PatternOptions,
    flat: F,
    mirror: M,
) -> Vec<Result<T, PatternError>>
where
    T: Send,
    F: Fn(&Panel) -> Result<T, PatternError> + Sync,
    M: Fn(&T, &TiVec<PanelVertex, PanelVertex>) -> T,
{
    let maps: Vec<Option<TiVec<PanelVertex, PanelVertex>>> =
        panels.par_iter().enumerate().map(|(i, p)| pair_map(&panels[second_of[i]?], p, plane, opts)).collect();
    let own: Vec<Option<Result<T, PatternError>>> =
        panels.par_iter().zip(&maps).map(|(p, m)| m.is_none().then(|| flat(p))).collect();
    let mirrored: Vec<Option<T>> = maps
        .iter()
        .zip(second_of)
        .map(|(map, first)| match (map, own[(*first)?].as_ref()) {
            (Some(map), Some(Ok(first))) => Some(mirror(first, map)),
            _ => None,
        })
        .collect();
    own.into_iter()
        .zip(mirrored)
        .zip(panels)
        .map(|((own, mirrored), p)| match (mirrored, own) {
            (Some(m), _) => Ok(m),
            (None, Some(own)) => own,
            (None, None) => flat(p),
        })
        .collect()
}

/// The seam step of a pass: with [`PatternOptions::negotiate_seams`], each
/// seam's sewn lengths negotiated between its sides from their free
/// flattenings (`free`, where the dart search left them; else flattened
/// here), a segment whose ratio a size run `carried` from its base size
/// ([`DartPlan::seam_ratios`]) at its 3D length times that; else none
/// (every seam held at its 3D length). Returns the sewn lengths and each
/// segment's ratio.
#[expect(clippy::too_many_arguments, reason = "the pass's panels, free flattenings and seams, and the run's ratios")]
fn sewn_lengths(
    panels: &[Panel],
    free: Vec<Option<Trial>>,
    seams: &[SeamChain],
    n_nodes: usize,
    opts: &PatternOptions,
    find_darts: bool,
    pairs: Pairs<'_>,
    carried: &[SeamRatio],
) -> Result<(SewnRatios, Vec<SeamRatio>), PatternError> {
    Ok(if opts.negotiate_seams {
        let free = if find_darts {
            free.into_iter().flatten().collect()
        } else {
            flatten_pairs(panels, pairs, opts, |p| flatten_free(p, seams, &opts.flatten), mirrored_trial)
                .into_iter()
                .collect::<Result<Vec<_>, _>>()?
        };
        negotiate(panels, &free, seams, n_nodes, opts.negotiation_power, carried)
    } else {
        (SewnRatios::new(), Vec::new())
    })
}

/// The figures of one piece (module docs): distortion `d`, thread strain,
/// ARAP's convergence, 3D area, strain hotspot, waist straightness, and
/// whether its sew and cut lines cross themselves.
#[expect(clippy::too_many_arguments, reason = "the piece's panel, flattening, placement and what the pass found")]
fn piece_report(
    t: &Template,
    panel: &Panel,
    flat: &Flattening,
    p: &PlacedPanel,
    d: Distortion,
    size: &str,
    found_darts: Vec<FoundDart>,
    [sew_line_self_intersects, cut_line_self_intersects]: [bool; 2],
) -> PieceReport {
    let area_3d_mm2 = panel
        .triangles
        .iter()
        .map(|f| {
            let [a, b, c] = f.map(|v| panel.positions[v]);
            0.5 * (b - a).cross(c - a).length()
        })
        .sum::<f64>()
        * 1e6;
    PieceReport {
        name: panel.name.clone(),
        size: size.to_string(),
        distortion: d,
        fabric: fabric_strain(
            &panel.positions.iter().map(|q| *q * 1e3).collect::<TiVec<_, _>>(),
            &panel.triangles,
            &p.uv_mm,
            DVec2::NEG_Y,
        ),
        iterations: flat.iterations,
        converged: flat.converged,
        fallback: flat.fallback,
        area_3d_mm2,
        hotspot: hotspot(t, panel, &p.uv_mm),
        waist_deviation_mm: waist_deviation(t, panel, &p.piece),
        sew_line_self_intersects,
        cut_line_self_intersects,
        found_darts,
    }
}

/// The mid-sagittal plane of a garment, `(n, d)` with `n·p = d` on it, from
/// the template's nodes tied to mirrored feature points
/// (`thigh_left`/`thigh_right`). A first estimate: [`Plane::bisecting`] the
/// pairs of points tied to one node each, or, where no point is (a girth
/// line split by extra ring nodes, nodes along a seam tied to the nearest
/// point: the princess dress), the mean of each point's nodes paired with
/// the mean of its mirror point's (where both have as many). Then, twice,
/// every node on the left of the plane is paired with the node nearest its
/// image across it, and the plane is bisected again from those pairs: exact
/// on a garment made symmetric (`refine::symmetry`), where the first
/// estimate alone was 0.6–0.8 mm off (the means; and the one-node points
/// of the princess dress, whose mirror pair's panels then missed their
/// vertex-for-vertex map, [`super::mirror`], by up to 0.78 mm), and a found
/// dart's chain, mirrored by nearest vertices, did not follow the refined
/// edges. `None` without such nodes.
fn mirror_plane(t: &Template, positions: &TiSlice<VertexId, DVec3>) -> Option<(DVec3, f64)> {
    let mut groups: BTreeMap<String, Vec<DVec3>> = BTreeMap::new();
    let mut nodes = Vec::with_capacity(t.nodes.len());
    for (i, n) in t.nodes.iter().enumerate() {
        let p = *positions.get(node_vertex(i as u32))?;
        groups.entry(n.point.to_string()).or_default().push(p);
        nodes.push(p);
    }
    let mirrored: Vec<(&Vec<DVec3>, &Vec<DVec3>)> = groups
        .iter()
        .filter(|(name, _)| name.contains("left"))
        .filter_map(|(name, left)| Some((left, groups.get(&mirror_name(name)?)?)))
        .filter(|(l, r)| l.len() == r.len())
        .collect();
    let unique: Vec<(DVec3, DVec3)> =
        mirrored.iter().filter(|(l, _)| l.len() == 1).map(|(l, r)| (l[0], r[0])).collect();
    let mean = |v: &[DVec3]| v.iter().sum::<DVec3>() / v.len() as f64;
    let means: Vec<(DVec3, DVec3)> = mirrored.iter().map(|(l, r)| (mean(l), mean(r))).collect();
    let mut plane = Plane::bisecting(&unique, None).or_else(|| Plane::bisecting(&means, None))?;
    for _ in 0..2 {
        let reflect = |p: DVec3| p - 2.0 * plane.signed_distance(p) * plane.normal;
        // a node on the plane is its own image: it says nothing of the plane's tilt
        let pairs: Vec<(DVec3, DVec3)> = nodes
            .iter()
            .filter(|&&p| plane.signed_distance(p) > 0.0)
            .filter_map(|&p| {
                let m = reflect(p);
                let q = nodes.iter().copied().min_by(|a, b| a.distance(m).total_cmp(&b.distance(m)))?;
                (plane.signed_distance(q) < 0.0).then_some((p, q))
            })
            .collect();
        plane = Plane::bisecting(&pairs, None).unwrap_or(plane);
    }
    Some((plane.normal, plane.offset))
}

/// What shapes the darts searched on `panel` ([`DartGuides`]): its grain
/// line's direction here, and `plane` where the panel is its own mirror
/// image across it — every vertex's reflection within the panel's longest
/// edge of one of its vertices (a skirt's whole front; a trouser's front
/// is not: its image is its mirror pair's); none unless
/// [`AutoDartOptions::guided`].
fn dart_guides(
    t: &Template,
    positions: &TiSlice<VertexId, DVec3>,
    panel: &Panel,
    plane: Option<(DVec3, f64)>,
    barrier: &DartBarrier,
    opts: &PatternOptions,
) -> DartGuides {
    if !opts.auto_darts.guided {
        return DartGuides::default();
    }
    let local = |set: &HashSet<VertexId>| -> HashSet<PanelVertex> {
        panel.global.iter_enumerated().filter(|(_, g)| set.contains(g)).map(|(l, _)| l).collect()
    };
    let (barrier, hanging) = (local(&barrier.girth_lines), local(&barrier.hanging));
    let grain = t.panels.iter().find(|p| p.name == panel.name).and_then(|p| {
        let (a, b) = (positions.get(node_vertex(p.grain.from))?, positions.get(node_vertex(p.grain.to))?);
        (*b - *a).try_normalize()
    });
    let own_image = plane.filter(|&(n, d)| {
        let reach = panel
            .triangles
            .iter()
            .flat_map(|f| (0..3).map(move |k| (f[k], f[(k + 1) % 3])))
            .map(|(a, b)| panel.positions[a].distance(panel.positions[b]))
            .fold(opts.mirror_tolerance_mm * 1e-3, f64::max);
        let index = crate::geom::query::PointGrid::new(&panel.positions.raw[..panel.unique], reach);
        panel.positions.raw[..panel.unique].iter().all(|&p| {
            let q = p - 2.0 * (n.dot(p) - d) * n;
            index.nearest_within(q, reach).is_some()
        })
    });
    DartGuides { grain, mirror: own_image, barrier, hanging }
}

/// `first`'s found darts mirrored across `plane` onto `second` (its mirror
/// pair): each chain vertex goes to the vertex of `second` nearest to its
/// mirror image, which must lie within
/// [`PatternOptions::mirror_tolerance_mm`], and the mirrored chain must be
/// a path of `second`'s edges that slits. `None` when it is not a mirror
/// image there (a scan): `second` is left unchanged then.
fn mirror_darts(
    first: &Panel,
    darts: &[FoundDart],
    second: &mut Panel,
    positions: &TiSlice<VertexId, DVec3>,
    (n, d): (DVec3, f64),
    opts: &PatternOptions,
) -> Option<Vec<FoundDart>> {
    let reflect = |p: DVec3| p - 2.0 * (n.dot(p) - d) * n;
    let tol = opts.mirror_tolerance_mm * 1e-3;
    let mut edges = std::collections::HashSet::new();
    for f in &second.triangles {
        for k in 0..3 {
            edges.insert(MeshEdge::new(f[k], f[(k + 1) % 3]));
        }
    }
    let mut trial = second.clone();
    let mut out = Vec::with_capacity(darts.len());
    for dart in darts {
        let legs = first.darts.iter().find(|l| l.name == dart.name)?;
        let mut chain = Vec::with_capacity(legs.a.len());
        for &l in &legs.a {
            let q = reflect(*positions.get(*first.global.get(l)?)?);
            // over the panel's vertices (not their dart copies), ties to the lower id: deterministic
            let (g, dist) = second.global.raw[..second.unique]
                .iter()
                .map(|&g| (g, positions.get(g).map_or(f64::INFINITY, |p| p.distance(q))))
                .min_by(|a, b| a.1.total_cmp(&b.1).then(a.0.cmp(&b.0)))?;
            if dist > tol {
                return None;
            }
            chain.push(second.local(g)?);
        }
        if chain.windows(2).any(|w| !edges.contains(&MeshEdge::new(w[0], w[1]))) {
            return None;
        }
        let name = dart.name.replacen(&first.name, &second.name, 1);
        trial.add_dart(&name, &chain).ok()?;
        out.push(FoundDart { name, apex: reflect(dart.apex), origin: DartOrigin::Mirrored, ..dart.clone() });
    }
    *second = trial;
    Some(out)
}

/// What [`search_darts`] found on one panel.
#[derive(Clone)]
struct Searched {
    /// The panel with its found darts slit open.
    panel: Panel,
    /// The darts, in the order found.
    darts: Vec<FoundDart>,
    /// The darted panel's flattening in the search (seams free when they are
    /// negotiated afterwards, else held at their 3D length).
    last: Trial,
}

/// Darts found where `panel` strains ([`insert_darts`], with the seams free
/// when they are negotiated afterwards).
fn search_darts(
    panel: &Panel,
    seams: &[SeamChain],
    n_nodes: usize,
    opts: &PatternOptions,
    search: &AutoDartOptions,
    guides: &DartGuides,
) -> Result<Searched, PatternError> {
    let free = SewnRatios::new();
    let holds = |p: &Panel| seam_chains(p, seams, &free, !opts.negotiate_seams);
    let flat = flatten_held(panel, &holds(panel), &opts.flatten).map_err(flatten_error(panel))?;
    let first = Trial { distortion: distortion(&panel.positions, &panel.triangles, &flat.uv), flat };
    // the search is asked for only when it is enabled ([`pattern`]); it stops at once below the target
    let min_intake = opts.min_dart_intake_mm * 1e-3;
    // the candidates are ranked at the search's looser tolerances, the winner kept at the flattening's
    let rank = FlattenOptions {
        tolerance: opts.flatten.tolerance.max(search.rank_tolerance),
        boundary_tolerance: opts.flatten.boundary_tolerance.max(search.rank_boundary_tolerance),
        ..opts.flatten
    };
    let run = |guides: &DartGuides| {
        insert_darts(panel, first.clone(), n_nodes, min_intake, search, guides, |p, pass| {
            let precision = if pass == Pass::Rank { &rank } else { &opts.flatten };
            let flat = flatten_held(p, &holds(p), precision).ok()?;
            Some(Trial { distortion: distortion(&p.positions, &p.triangles, &flat.uv), flat })
        })
    };
    // the hanging region closed first; opened where the piece cannot meet the bar without it
    let closed = DartGuides { barrier: guides.barrier.union(&guides.hanging).copied().collect(), ..guides.clone() };
    let (mut panel, mut last, mut darts) = run(&closed);
    if !guides.hanging.is_empty() && last.distortion.strain_p95 > search.hanging_strain_p95 {
        let open = run(guides);
        if open.1.distortion.strain_p95 < last.distortion.strain_p95 {
            (panel, last, darts) = open;
        }
    }
    Ok(Searched { panel, darts, last })
}

/// The seam reports and dart checks of the laid-out pieces, and the pattern.
#[expect(clippy::too_many_arguments, reason = "the parts of one pass of pattern_once, handed over once")]
fn finish(
    t: &Template,
    positions: &TiSlice<VertexId, DVec3>,
    size: &str,
    panels: Vec<Panel>,
    seams: &[SeamChain],
    pieces: Vec<PatternPiece>,
    placed: Vec<PlacedPanel>,
    reports: Vec<PieceReport>,
) -> (GarmentPattern, Vec<DartCheck>) {
    let seam_reports = seams
        .iter()
        .map(|s| {
            // sewn length from the seam's start to each of its vertices (a dart
            // opening on the seam is closed: the edges either side of its mouth
            // end on the mouth's two copies)
            let side = |pi: usize| -> Vec<f64> {
                let uv = &placed[pi].uv_mm;
                let edges = panels[pi].seam_edges(&s.chain).unwrap_or_default();
                std::iter::once(0.0)
                    .chain(edges.iter().scan(0.0, |sum, [u, w]| {
                        *sum += uv[*u].distance(uv[*w]);
                        Some(*sum)
                    }))
                    .collect()
            };
            let (a, b) = (side(s.panel_a), side(s.panel_b));
            let chain_3d: Vec<DVec3> = s.chain.iter().map(|&g| positions[g]).collect();
            let (la, lb) = (a.last().copied().unwrap_or(0.0), b.last().copied().unwrap_or(0.0));
            let notch_mismatch_mm = t
                .notches
                .iter()
                .filter_map(|n| s.chain.iter().position(|&g| g == node_vertex(n.node)))
                .filter_map(|k| Some((a.get(k)? - b.get(k)?).abs()))
                .fold(0.0, f64::max);
            SeamReport {
                name: s.name.clone(),
                piece_a: panels[s.panel_a].name.clone(),
                piece_b: panels[s.panel_b].name.clone(),
                length_3d_mm: polyline_length_3d(&chain_3d) * 1e3,
                length_a_mm: la,
                length_b_mm: lb,
                mismatch_mm: (la - lb).abs(),
                notch_mismatch_mm,
            }
        })
        .collect();
    let mut seam_reports: Vec<SeamReport> = seam_reports;
    for (pi, panel) in panels.iter().enumerate() {
        for d in &panel.darts {
            let leg = |ids: &[PanelVertex]| -> Vec<DVec2> { ids.iter().map(|&l| placed[pi].uv_mm[l]).collect() };
            let (la, lb) = (polyline_length(&leg(&d.a)), polyline_length(&leg(&d.b)));
            let chain_3d: Vec<DVec3> = d.a.iter().map(|&l| panel.positions[l]).collect();
            seam_reports.push(SeamReport {
                name: d.name.clone(),
                piece_a: panel.name.clone(),
                piece_b: panel.name.clone(),
                length_3d_mm: polyline_length_3d(&chain_3d) * 1e3,
                length_a_mm: la,
                length_b_mm: lb,
                mismatch_mm: (la - lb).abs(),
                notch_mismatch_mm: 0.0,
            });
        }
    }
    let mut darts = Vec::new();
    for (pi, panel) in panels.iter().enumerate() {
        let rim = panel.rim();
        for d in &panel.darts {
            if let Some(opening) = dart_opening(&rim, &placed[pi].uv_mm, d) {
                darts.push((d.name.clone(), opening, reports[pi].sew_line_self_intersects));
            }
        }
    }
    let g = GarmentPattern {
        style: t.name.clone(),
        size: size.to_string(),
        pieces,
        reports,
        seams: seam_reports,
        darts_left_out: Vec::new(),
        dart_plan: DartPlan::default(),
        cut_pairs: Vec::new(),
    };
    (g, darts)
}

/// Centroid of the edges strained above the 95th percentile and the nearest template node.
fn hotspot(t: &Template, panel: &Panel, uv_mm: &TiSlice<PanelVertex, DVec2>) -> Option<StrainHotspot> {
    let mut edges: Vec<(f64, DVec2)> = Vec::new();
    for f in &panel.triangles {
        for k in 0..3 {
            let (a, b) = (f[k], f[(k + 1) % 3]);
            if a < b {
                let l3 = panel.positions[a].distance(panel.positions[b]) * 1e3;
                if l3 > 0.0 {
                    edges.push(((uv_mm[a].distance(uv_mm[b]) / l3 - 1.0).abs(), 0.5 * (uv_mm[a] + uv_mm[b])));
                }
            }
        }
    }
    if edges.is_empty() {
        return None;
    }
    edges.sort_by(|x, y| y.0.total_cmp(&x.0));
    let top = &edges[..edges.len().div_ceil(20)];
    let at = top.iter().map(|e| e.1).sum::<DVec2>() / top.len() as f64;
    // the panel's template nodes: its first local vertices (ascending fine ids, nodes first)
    let (near, distance_mm) = panel
        .global
        .iter_enumerated()
        .map_while(|(l, &g)| Some((l, vertex_node(g, t.nodes.len())?)))
        .map(|(l, node)| (t.nodes[node as usize].point.as_str().to_string(), uv_mm[l].distance(at)))
        .min_by(|a, b| a.1.total_cmp(&b.1))?;
    Some(StrainHotspot { at, near, distance_mm })
}

/// Straightness of the waist line on the sew line (module docs).
fn waist_deviation(t: &Template, panel: &Panel, piece: &PatternPiece) -> Option<f64> {
    let rim = panel.rim();
    let n = rim.len();
    let kind = |k: usize| -> Option<bool> {
        let node = vertex_node(panel.global[rim[k]], t.nodes.len())?;
        t.nodes.get(node as usize).map(|node| node.point.as_str().starts_with("waist_"))
    };
    // start just after a coarse node that is not on the waist, so the waist run is contiguous
    let start = (0..n).find(|&k| kind(k) == Some(false))?;
    let waist: Vec<usize> = (1..=n).map(|i| (start + i) % n).filter(|&k| kind(k) == Some(true)).collect();
    let (&first, &last) = (waist.first()?, waist.last()?);
    let span = (last + n - first) % n;
    if span == 0 {
        return None;
    }
    let line: Vec<DVec2> = (0..=span).map(|i| piece.sew_line[(first + i) % n]).collect();
    Some(deviation_from_chord(&line))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::refine::subdivide::{refine, RefineMesh, RefineOptions, Refined};
    use crate::template::codec::decode;
    use crate::template::format::Relocation;
    use crate::template::library::{builtin, reference_body};

    /// `t` decoded on the reference body and refined (default options).
    fn refined_on_reference(t: &Template) -> (RefineMesh, crate::refine::lineage::Lineage) {
        let body = reference_body().expect("reference body");
        let m0 = decode(t, &body, Relocation::Eq1Frame).expect("decode");
        let edges: Vec<(u32, u32)> = t.edges.iter().map(|e| (e.start, e.end)).collect();
        let coarse = RefineMesh::from_coarse(&m0, &edges).expect("coarse");
        let Refined { mesh, lineage, .. } = refine(coarse, &RefineOptions::default(), |_, _| {}).expect("refine");
        (mesh, lineage)
    }

    /// The built-in trousers refined on the reference body, and pattern
    /// options without found darts.
    fn trousers_without_found_darts() -> (Template, RefineMesh, crate::refine::lineage::Lineage, PatternOptions) {
        let t = builtin().expect("library").into_iter().find(|t| t.name == "trousers").expect("trousers");
        let (fine, lineage) = refined_on_reference(&t);
        let plain = PatternOptions {
            auto_darts: AutoDartOptions { enabled: false, ..Default::default() },
            ..Default::default()
        };
        (t, fine, lineage, plain)
    }

    /// The built-in skirt with only its two back darts, and with none.
    fn skirts() -> (Template, Template) {
        let mut t = builtin().expect("library").remove(0);
        t.darts.retain(|d| d.panel == "back");
        assert_eq!(t.darts.len(), 2, "the skirt declares two back darts");
        t.validate().expect("valid");
        let mut none = t.clone();
        none.darts.clear();
        (t, none)
    }

    #[test]
    fn declared_darts_are_slit_open_and_sewn_to_equal_legs() {
        let (t, plain) = skirts();
        let (fine, lineage) = refined_on_reference(&t);
        // the declared darts alone: found darts on the front would change the side seams'
        // negotiated lengths, and so the back, differently with and without them
        let opts = PatternOptions {
            auto_darts: AutoDartOptions { enabled: false, ..AutoDartOptions::default() },
            ..PatternOptions::default()
        };
        let with = pattern(&t, &fine.positions, &fine.triangles, &lineage, "ref", &opts).expect("pattern");
        let without = pattern(&plain, &fine.positions, &fine.triangles, &lineage, "ref", &opts).expect("pattern");
        assert!(with.darts_left_out.is_empty(), "{:?}", with.darts_left_out);
        let back = |g: &GarmentPattern| g.reports.iter().find(|r| r.name == "back").cloned().expect("back");
        let (b1, b0) = (back(&with), back(&without));
        eprintln!("back piece without darts {:?}\nwith two darts {:?}", b0.distortion, b1.distortion);
        for name in ["dart_back_left", "dart_back_right"] {
            let legs = with.seams.iter().find(|s| s.name == name).expect("dart report");
            assert!(legs.mismatch_mm < 1e-6, "{legs:?}");
            let piece = with.pieces.iter().find(|p| p.name == "back").expect("piece");
            let line = piece.internal_lines.iter().find(|l| l.name == name).expect("dart line");
            let opening = line.points[0].distance(line.points[line.points.len() - 1]);
            assert!(opening > 5.0, "{name} opens by {opening:.2} mm");
        }
        assert!(!b1.sew_line_self_intersects && !b1.cut_line_self_intersects);
        assert_eq!(b1.distortion.flipped, 0);
        assert!(b1.distortion.strain_p95 < b0.distortion.strain_p95, "darts relieve the strain");
    }

    /// Planted: a plan whose every seam segment's ratio is 1.01, carried to
    /// a size, sews each seam at 1.01 × its 3D length on both sides, and
    /// the pattern's plan carries those ratios bit for bit; a base size's
    /// plan records its negotiated ratios (sewn over 3D, one per segment).
    #[test]
    fn a_carried_plan_sews_each_seam_at_its_3d_length_times_the_base_ratio() {
        let (t, fine, lineage, plain) = trousers_without_found_darts();
        let run = |plan: Option<&DartPlan>| {
            pattern_with_plan(&t, &fine.positions, &fine.triangles, &lineage, "ref", &plain, plan).expect("pattern")
        };
        let base = run(None);
        assert!(!base.dart_plan.seam_ratios.is_empty());
        assert!(base.dart_plan.seam_ratios.iter().any(|(_, r)| (r - 1.0).abs() > 1e-3), "the base negotiates");
        let plan = DartPlan {
            seam_ratios: base.dart_plan.seam_ratios.iter().map(|&(k, _)| (k, 1.01)).collect(),
            ..base.dart_plan.clone()
        };
        let carried = run(Some(&plan));
        for s in &carried.seams {
            let want = 1.01 * s.length_3d_mm;
            assert!((s.length_a_mm - want).abs() < 0.05 && (s.length_b_mm - want).abs() < 0.05, "{s:?}");
        }
        assert_eq!(carried.dart_plan.seam_ratios, plan.seam_ratios);
    }

    #[test]
    fn negotiated_seams_match_on_both_sides_and_strain_less() {
        let (t, fine, lineage, plain) = trousers_without_found_darts();
        let held = PatternOptions { negotiate_seams: false, ..plain };
        let run =
            |o: &PatternOptions| pattern(&t, &fine.positions, &fine.triangles, &lineage, "ref", o).expect("pattern");
        let (negotiated, at_3d) = (run(&plain), run(&held));
        for s in &negotiated.seams {
            assert!(s.mismatch_mm < 1e-2 && s.notch_mismatch_mm < 1e-2, "{s:?}");
        }
        // held at 3D length, a seam's sides equal its 3D length; negotiated, the crotch seams give
        for s in &at_3d.seams {
            assert!((s.length_a_mm - s.length_3d_mm).abs() < 1e-2, "{s:?}");
        }
        let moved = negotiated.seams.iter().map(|s| (s.length_a_mm - s.length_3d_mm).abs()).fold(0.0, f64::max);
        assert!(moved > 1.0, "some seam takes another length than in 3D: {moved:.3} mm");
        let p95 = |g: &GarmentPattern| g.reports.iter().map(|r| r.distortion.strain_p95).fold(0.0, f64::max);
        eprintln!("worst p95: seams at 3D length {:.4}, negotiated {:.4}", p95(&at_3d), p95(&negotiated));
        assert!(p95(&negotiated) < p95(&at_3d));
        for r in &negotiated.reports {
            assert_eq!(r.distortion.flipped, 0, "{}", r.name);
            assert!(!r.sew_line_self_intersects, "{}", r.name);
        }
    }

    #[test]
    fn a_plan_carried_onto_its_own_mesh_gives_the_same_pattern() {
        // planted answer: the trousers on the reference body, darts searched; the plan it
        // returns, carried onto the same mesh, slits the same lines and gives the same pieces
        let t = builtin().expect("library").into_iter().find(|t| t.name == "trousers").expect("trousers");
        let (fine, lineage) = refined_on_reference(&t);
        let opts = PatternOptions {
            auto_darts: AutoDartOptions { target_strain_p95: 0.0, parallel: false, ..Default::default() },
            ..Default::default()
        };
        let found = pattern(&t, &fine.positions, &fine.triangles, &lineage, "ref", &opts).expect("pattern");
        let plan = found.dart_plan.clone();
        assert!(!plan.found.is_empty(), "a zero target finds darts");
        for r in &found.reports {
            assert!(r.found_darts.len() <= 2, "{}: at most two found darts per piece by default", r.name);
        }
        let carried = pattern_with_plan(&t, &fine.positions, &fine.triangles, &lineage, "ref", &opts, Some(&plan))
            .expect("carried");
        assert_eq!(carried.dart_plan, plan);
        for (a, b) in found.pieces.iter().zip(&carried.pieces) {
            assert_eq!(a.name, b.name);
            assert_eq!(a.sew_line.len(), b.sew_line.len(), "{}", a.name);
            let off = a.sew_line.iter().zip(&b.sew_line).map(|(p, q)| p.distance(*q)).fold(0.0, f64::max);
            assert!(off < 1e-6, "{}: sew lines differ by {off} mm", a.name);
        }
        // a chain that is not a line of the panel is a typed error, not a panic
        let mut bad = plan.clone();
        bad.found[0].chain = vec![VertexId(u32::MAX), VertexId(0)];
        let e =
            pattern_with_plan(&t, &fine.positions, &fine.triangles, &lineage, "ref", &opts, Some(&bad)).unwrap_err();
        assert!(matches!(e, PatternError::CarriedDart { .. }), "{e}");
    }
}
