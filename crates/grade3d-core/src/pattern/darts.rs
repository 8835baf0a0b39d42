//! Darts where the flattening strains most: greedy, distortion-driven cut
//! insertion.
//!
//! # Method
//!
//! A doubly curved panel cannot be laid flat at true length; a pattern maker
//! takes the excess out in darts, placed where the distortion gathers (the
//! cutting lines of the energy-model flattening, Wang, Smith & Yuen 2002,
//! seed 000 ref. [6]; boundary cuts as a topological operator that makes a
//! surface flattenable, Kwok, Wang et al. 2015, DOI 10.1115/1.4031023).
//! Given a panel and its flattening, one round of [`insert_darts`]:
//!
//! 1. measures the strain of every vertex, `s(v) = mean |ℓ′/ℓ − 1|` over its
//!    edges (`ℓ` the 3D length, `ℓ′` the 2D one);
//! 2. takes the [`AutoDartOptions::candidates`] most strained interior
//!    vertices, each at least one ring away from an earlier candidate's path,
//!    as apexes, and joins each to the outline by its shortest path along mesh
//!    edges (Dijkstra on 3D edge lengths) through interior vertices that are
//!    not template nodes, ending on an outline vertex that may open (not a
//!    template node, not on a dart already there) and, where the caller
//!    gives the piece's grain ([`DartGuides::grain`]), that lies along the
//!    grain from the apex, on an outline that runs across the grain there,
//!    both within [`AutoDartOptions::max_grain_angle_deg`]: a dart runs with
//!    the grain and opens on an edge across it (a waist, a shoulder), as a
//!    pattern maker drafts it — not across the piece from a
//!    side seam, where the search found 8 cm darts at the thigh of an
//!    authored skirt (issue #18);
//!    on a piece that is its own mirror image ([`DartGuides::mirror`], a
//!    skirt's whole front), each candidate comes with its mirror image: the
//!    path from the interior vertex nearest the apex's reflection to the
//!    outline vertex nearest the mouth's, slit together (a pattern maker
//!    drafts a symmetric piece's darts in pairs; the search put one dart on
//!    one side of it); no dart runs through a vertex of
//!    [`DartGuides::barrier`] (the piece's girth lines);
//! 3. slits the panel along each path ([`Panel::add_dart`]), flattens it again
//!    (the caller's flattening, which sews the new legs to equal length) and
//!    keeps the candidate with the lowest 95th-percentile strain, provided
//!    the flattening has no flipped triangle, the sew line (darts closed)
//!    does not cross itself, every dart's straight legs (mouth → apex) stay
//!    inside the piece, every dart opens by at least the intake the
//!    caller asks for — a cut that wants to overlap marks a saddle, where a
//!    dart cannot help — and the 95th percentile drops by at least
//!    [`AutoDartOptions::min_gain`].
//!
//! Rounds repeat until the piece meets [`AutoDartOptions::target_strain_p95`],
//! holds [`AutoDartOptions::max_darts`] found darts (a mirrored pair is
//! two: it is tried only while both fit), or no candidate helps.
//!
//! # Contract
//!
//! Pure: data in, data out; the flattening is the caller's closure, so this
//! module knows nothing of seams or options beyond its own. A candidate
//! whose slit or flattening fails (or panics) is skipped, never an error. The result is
//! the panel (with its new darts), its flattening and what each dart did; when
//! nothing helps it is the input unchanged. Deterministic: ties break on
//! vertex ids.

use std::cmp::Ordering;
use std::collections::{BinaryHeap, HashSet};

use glam::{DVec2, DVec3};
use serde::{Deserialize, Serialize};

use super::assemble::{polyline_length_3d, self_intersects};
use super::flatten::{Distortion, Flattening};
use typed_index_collections::{TiSlice, TiVec};

use super::panels::{DartLegs, Panel, PanelFace, PanelVertex};
use crate::geom::polyline::segment_crosses_polygon;
use crate::refine::lineage::vertex_node;

/// Knobs of the dart search.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct AutoDartOptions {
    /// Search at all. Default true.
    pub enabled: bool,
    /// A piece whose 95th-percentile edge strain is at or below this gets no
    /// dart, and the search stops once a piece reaches it (fraction). Default 0.025.
    pub target_strain_p95: f64,
    /// Most darts added to one piece, a mirrored pair on a piece that is
    /// its own mirror image ([`DartGuides::mirror`]) counting two (count).
    /// Default 2 (issue #14: a pattern maker drafts one or two back darts
    /// per side, not a fan; the search with 8 put 3–5 on a trouser back,
    /// intakes up to 77 mm; a skirt back that is its own mirror image takes
    /// one pair — a second pair on the authored A-line skirt moved its
    /// waist's grade points by up to 22 mm from size to size).
    pub max_darts: usize,
    /// Apexes tried per dart (count; each costs one flattening). Default 24.
    pub candidates: usize,
    /// Least drop of the 95th-percentile strain that earns a dart (fraction).
    /// Default 0.0005: a small step often opens the way to a larger one.
    pub min_gain: f64,
    /// Shortest dart, along its legs, mm. Default 20.
    pub min_length_mm: f64,
    /// Flatten a round's candidates side by side on rayon's global pool
    /// (the process's one thread budget; issue #15 replaced a scoped thread
    /// per CPU inside each pool worker); false: one after another on the
    /// caller's thread. The result is the same either way. Default true.
    pub parallel: bool,
    /// ARAP's relative energy tolerance in the flattenings that *rank* a
    /// round's candidates ([`Pass::Rank`]; the flattening's own tolerance
    /// where that is looser), dimensionless. The winner is flattened again
    /// at the flattening's own tolerances ([`Pass::Keep`]) before it is
    /// kept, so only the ranking sees it. Default 1e-4.
    pub rank_tolerance: f64,
    /// Relative error of the held lengths (the dart legs sewn to each other,
    /// held seams) at which a ranking flattening may stop, dimensionless
    /// (issue #15: holding them to the flattening's own 1e-5 took most of
    /// the search's iterations; on the ASTM chart's size 8 ranking at 1e-3
    /// picks the same darts as at 1e-5, and the bodice's search costs 17 %
    /// less). Default 1e-3.
    pub rank_boundary_tolerance: f64,
    /// Largest angle between a dart (apex → mouth, in 3D) and its piece's
    /// grain line, and between the outline at its mouth and the grain's
    /// perpendicular, where the caller gives the grain
    /// ([`DartGuides::grain`]), degrees; 90: any. Default 30 (module docs,
    /// step 2).
    pub max_grain_angle_deg: f64,
    /// A piece whose darts, kept out of the region that hangs below the
    /// garment's lowest girth ([`DartGuides::hanging`]), leave it above this
    /// p95 edge strain is searched again with that region open (fraction).
    /// Default 0.04, issue #14's strain bar: a skirt falls straight below
    /// the hip and wants no dart there (the search slit the authored skirt's
    /// front from the hem nearly to the hip, 58–70 cm, and they opened by
    /// up to 225 mm once the seams were negotiated), unless its design
    /// flares in a way no flat piece can (the curve skirt's lower front,
    /// between two ellipses of different shape: 19 % p95 without darts,
    /// 1.8 % with).
    pub hanging_strain_p95: f64,
    /// Follow the rules of [`DartGuides`] at all (the caller's guides are
    /// used only then); the pipeline turns it on for a template whose
    /// defaults ask for it (`GradingDefaults::guided_darts`). Default false.
    pub guided: bool,
}

/// What the caller knows of a piece that shapes its darts (module docs,
/// step 2).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct DartGuides {
    /// The piece's grain direction in 3D (either sense); `None`: darts run
    /// any way.
    pub grain: Option<DVec3>,
    /// The plane `(n, d)` (`n·p = d`, `n` unit) the piece is its own
    /// mirror image across; `None`: darts are not paired.
    pub mirror: Option<(DVec3, f64)>,
    /// Interior vertices no dart runs through: the piece's girth lines (a
    /// waist dart ends above the hip it shapes, as a pattern maker ends it
    /// short of the fullest girth; the search ran the authored skirt's front
    /// darts 9 cm past the hip line to the thigh).
    pub barrier: HashSet<PanelVertex>,
    /// Interior vertices of the region that hangs below the lowest girth:
    /// the caller searches with them closed first, and opens them only where
    /// the piece stays above [`AutoDartOptions::hanging_strain_p95`]
    /// ([`super::garment`]); [`insert_darts`] itself does not read them.
    pub hanging: HashSet<PanelVertex>,
}

/// Which flattening [`insert_darts`] asks its caller for.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Pass {
    /// One that ranks a round's candidates: it may stop at
    /// [`AutoDartOptions::rank_tolerance`] and
    /// [`AutoDartOptions::rank_boundary_tolerance`].
    Rank,
    /// The winner's, kept as the panel's flattening: at full precision.
    Keep,
}

impl Default for AutoDartOptions {
    fn default() -> Self {
        Self {
            enabled: true,
            target_strain_p95: 0.025,
            max_darts: 2,
            candidates: 24,
            min_gain: 0.0005,
            min_length_mm: 20.0,
            parallel: true,
            rank_tolerance: 1e-4,
            rank_boundary_tolerance: 1e-3,
            max_grain_angle_deg: 30.0,
            hanging_strain_p95: 0.04,
            guided: false,
        }
    }
}

/// A flattening and its distortion.
#[derive(Debug, Clone, PartialEq)]
pub struct Trial {
    /// The flattening (2D positions in metres).
    pub flat: Flattening,
    /// Its distortion.
    pub distortion: Distortion,
}

/// What one found dart did.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, utoipa::ToSchema)]
pub struct FoundDart {
    /// Dart name.
    pub name: String,
    /// Length of its legs in 3D, mm.
    pub length_mm: f64,
    /// Its opening on the outline, mm.
    pub intake_mm: f64,
    /// 95th-percentile strain of the piece before it (fraction), in the
    /// search's flattening (with the seams free when they are negotiated
    /// afterwards, [`super::garment`]).
    pub strain_p95_before: f64,
    /// And with it (fraction), in the same flattening.
    pub strain_p95_after: f64,
    /// Apex, 3D, metres (where the strain gathered).
    #[schema(value_type = Vec<f64>, min_items = 3, max_items = 3)]
    pub apex: DVec3,
    /// How this piece got it.
    #[serde(default)]
    pub origin: DartOrigin,
}

/// How a piece got a found dart (issue #14: one dart plan per run, mirrored
/// onto mirror pairs).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize, utoipa::ToSchema)]
#[serde(rename_all = "snake_case")]
pub enum DartOrigin {
    /// Searched on this piece, where it strained ([`insert_darts`]); the
    /// strain figures are the search's.
    #[default]
    Found,
    /// Carried from the run's base size (the strain figures are this
    /// piece's, before and after alike: nothing was searched here).
    Carried,
    /// Mirrored from its mirror pair's dart, or, on a piece that is its own
    /// mirror image, the mirror image of the dart found before it (the
    /// strain figures are the search's).
    Mirrored,
}

/// Signed opening of a dart in a flattening, in the units of `uv`: the gap
/// between its two mouths on the sew line, negative when the legs cross (the
/// bridge from the first mouth to the second points against the sew line's
/// run). `None` when a mouth is not on the rim.
pub fn dart_opening(rim: &[PanelVertex], uv: &TiSlice<PanelVertex, DVec2>, dart: &DartLegs) -> Option<f64> {
    let n = rim.len();
    let (Some(i), Some(j)) = (rim.iter().position(|&v| v == dart.a[0]), rim.iter().position(|&v| v == dart.b[0]))
    else {
        return None;
    };
    let at = |l: PanelVertex| uv.get(l).copied();
    // the bridge x → y runs along the sew line: inverted if it points back
    let (x, y) = if (i + 1) % n == j { (i, j) } else { (j, i) };
    let (w, z) = (rim[(x + n - 1) % n], rim[(y + 1) % n]);
    let bridge = at(rim[y])? - at(rim[x])?;
    let sign = if bridge.dot(at(z)? - at(w)?) < 0.0 { -1.0 } else { 1.0 };
    Some(sign * bridge.length())
}

/// Strain of every vertex: the mean `|ℓ′/ℓ − 1|` over its edges (module docs, step 1).
pub fn vertex_strain(
    positions: &TiSlice<PanelVertex, DVec3>,
    triangles: &TiSlice<PanelFace, [PanelVertex; 3]>,
    uv: &TiSlice<PanelVertex, DVec2>,
) -> TiVec<PanelVertex, f64> {
    let mut sum: TiVec<PanelVertex, f64> = TiVec::from(vec![0.0; positions.len()]);
    let mut count: TiVec<PanelVertex, u32> = TiVec::from(vec![0u32; positions.len()]);
    for f in triangles {
        for k in 0..3 {
            let (a, b) = (f[k], f[(k + 1) % 3]);
            let l3 = positions[a].distance(positions[b]);
            if l3 <= 0.0 {
                continue;
            }
            let s = (uv[a].distance(uv[b]) / l3 - 1.0).abs();
            for v in [a, b] {
                sum[v] += s;
                count[v] += 1;
            }
        }
    }
    sum.iter().zip(&count).map(|(&s, &c)| if c > 0 { s / f64::from(c) } else { 0.0 }).collect()
}

/// Inserts darts into `panel` where its flattening `first` strains most
/// (module docs). Vertices whose fine id is below `n_nodes` (the template's
/// node count) are template nodes (never cut through, never a mouth); `min_intake` is the least
/// opening a dart must have, in metres; `flatten` flattens a candidate panel
/// (called from several threads at once under [`AutoDartOptions::parallel`]),
/// at the precision [`Pass`] asks for: the candidates are ranked by
/// [`Pass::Rank`] flattenings, and the best is flattened again with
/// [`Pass::Keep`] and kept if that one too is acceptable and gains enough
/// (else the next best, in rank order).
pub fn insert_darts(
    panel: &Panel,
    first: Trial,
    n_nodes: usize,
    min_intake: f64,
    opts: &AutoDartOptions,
    guides: &DartGuides,
    flatten: impl Fn(&Panel, Pass) -> Option<Trial> + Sync,
) -> (Panel, Trial, Vec<FoundDart>) {
    let mut panel = panel.clone();
    let mut best = first;
    let mut found = Vec::new();
    if !opts.enabled {
        return (panel, best, found);
    }
    while found.len() < opts.max_darts && best.distortion.strain_p95 > opts.target_strain_p95 {
        let before = best.distortion.strain_p95;
        let names = [found.len() + 1, found.len() + 2].map(|k| format!("dart_auto_{}_{k}", panel.name));
        // a mirrored pair is two darts: it must fit in what is left of the cap
        let mut paths = candidate_paths(&panel, &best.flat.uv, n_nodes, opts, guides);
        paths.retain(|p| found.len() + p.len() <= opts.max_darts);
        if paths.is_empty() {
            break;
        }
        // a candidate that panics is skipped like one that fails: its own result, in its own
        // place, so that the others stay paired with their paths (issue #16: a panicking
        // thread's whole chunk came back empty and shifted every later result)
        let try_one = |path: &Vec<Vec<PanelVertex>>| -> Option<(Panel, Trial, f64)> {
            std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
                let mut trial_panel = panel.clone();
                for (chain, name) in path.iter().zip(&names) {
                    trial_panel.add_dart(name, chain).ok()?;
                }
                let trial = flatten(&trial_panel, Pass::Rank)?;
                let intake = acceptable(&trial_panel, &trial, min_intake)?;
                Some((trial_panel, trial, intake))
            }))
            .ok()
            .flatten()
        };
        // candidates are independent: flattened side by side on rayon's pool (the process's one
        // thread budget, issue #15), results in candidate order
        let results: Vec<Option<(Panel, Trial, f64)>> = if opts.parallel {
            use rayon::prelude::*;
            paths.par_iter().map(try_one).collect()
        } else {
            paths.iter().map(try_one).collect()
        };
        // ranked by p95, candidate order on ties (deterministic: a stable sort); the first whose
        // kept flattening is still acceptable and still gains enough wins
        let gains = |t: &Trial| t.distortion.strain_p95 <= before - opts.min_gain;
        let mut ranked: Vec<(Panel, Trial, Vec<Vec<PanelVertex>>)> = paths
            .into_iter()
            .zip(results)
            .filter_map(|(path, r)| r.map(|(p, t, _)| (p, t, path)))
            .filter(|(_, t, _)| gains(t))
            .collect();
        ranked.sort_by(|a, b| a.1.distortion.strain_p95.total_cmp(&b.1.distortion.strain_p95));
        let winner = ranked.into_iter().find_map(|(trial_panel, _, path)| {
            let kept = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
                let trial = flatten(&trial_panel, Pass::Keep)?;
                let intake = acceptable(&trial_panel, &trial, min_intake)?;
                Some((trial, intake))
            }))
            .ok()
            .flatten()?;
            gains(&kept.0).then_some((trial_panel, kept.0, path, kept.1))
        });
        let Some((next, trial, chains, intake)) = winner else { break };
        for (k, (path, name)) in chains.iter().zip(&names).enumerate() {
            found.push(FoundDart {
                name: name.clone(),
                length_mm: path_length(&next, path) * 1e3,
                intake_mm: intake * 1e3,
                strain_p95_before: before,
                strain_p95_after: trial.distortion.strain_p95,
                apex: next.positions[path[path.len() - 1]],
                origin: if k == 0 { DartOrigin::Found } else { DartOrigin::Mirrored },
            });
        }
        panel = next;
        best = trial;
    }
    (panel, best, found)
}

/// The candidate's smallest dart opening, if the flattening is acceptable
/// (no flips, the sew line does not cross itself, every dart opens by
/// `min_intake`).
fn acceptable(panel: &Panel, trial: &Trial, min_intake: f64) -> Option<f64> {
    if trial.distortion.flipped > 0 {
        return None;
    }
    let rim = panel.rim();
    let uv = &trial.flat.uv;
    let sew: Vec<DVec2> = rim.iter().map(|&l| uv[l]).collect();
    if self_intersects(&sew) {
        return None;
    }
    let mut least = f64::INFINITY;
    for d in &panel.darts {
        // a dart a pattern maker can draw: straight legs from its mouth to its apex inside the
        // piece (a mouth on a concave seam, the back crotch, puts them outside: a V-slit)
        let (Some(&a), Some(&apex), Some(&b)) = (d.a.first(), d.a.last(), d.b.first()) else { return None };
        let (a, apex, b) = (uv[a], uv[apex], uv[b]);
        if segment_crosses_polygon(a, apex, &sew) || segment_crosses_polygon(apex, b, &sew) {
            return None;
        }
        let opening = dart_opening(&rim, uv, d)?;
        if opening < min_intake {
            return None;
        }
        least = least.min(opening);
    }
    Some(least)
}

/// Dijkstra queue entry: distance, vertex (smallest first).
#[derive(PartialEq)]
struct Entry(f64, PanelVertex);

impl Eq for Entry {}

impl PartialOrd for Entry {
    fn partial_cmp(&self, other: &Self) -> Option<Ordering> {
        Some(self.cmp(other))
    }
}

impl Ord for Entry {
    fn cmp(&self, other: &Self) -> Ordering {
        other.0.total_cmp(&self.0).then_with(|| other.1.cmp(&self.1))
    }
}

/// The candidates of one round (module docs, step 2): each a path from an
/// outline vertex that may open to an apex, as local ids, and on a
/// mirror-symmetric piece its mirror image after it.
fn candidate_paths(
    panel: &Panel,
    uv: &TiSlice<PanelVertex, DVec2>,
    n_nodes: usize,
    opts: &AutoDartOptions,
    guides: &DartGuides,
) -> Vec<Vec<Vec<PanelVertex>>> {
    // a template node on the panel being searched (dart copies included)
    let is_node = |v: PanelVertex| panel.global.get(v).is_some_and(|&g| vertex_node(g, n_nodes).is_some());
    let n = panel.positions.len();
    let mut adjacency: TiVec<PanelVertex, Vec<PanelVertex>> = TiVec::from(vec![Vec::new(); n]);
    for f in &panel.triangles {
        for k in 0..3 {
            let (a, b) = (f[k], f[(k + 1) % 3]);
            adjacency[a].push(b);
            adjacency[b].push(a);
        }
    }
    for list in &mut adjacency {
        list.sort_unstable();
        list.dedup();
    }
    let on_outline: HashSet<PanelVertex> = panel.outline.iter().copied().collect();
    let on_dart: HashSet<PanelVertex> = panel.darts.iter().flat_map(|d| d.a.iter().chain(&d.b).copied()).collect();
    let strain = vertex_strain(&panel.positions, &panel.triangles, uv);
    // a barrier vertex is closed to a dart like a template node
    let is_node = |v: PanelVertex| is_node(v) || guides.barrier.contains(&v);
    let mut order: Vec<PanelVertex> =
        panel.positions.keys().filter(|v| !on_outline.contains(v) && !is_node(*v)).collect();
    order.sort_by(|&a, &b| strain[b].total_cmp(&strain[a]).then(a.cmp(&b)));
    // a mouth along the grain from its apex, on an outline that runs across the grain there
    // (any outline vertex without a grain)
    let (cos_max, sin_max) = (opts.max_grain_angle_deg.to_radians().cos(), opts.max_grain_angle_deg.to_radians().sin());
    let n_out = if guides.grain.is_some() { panel.outline.len() } else { 0 };
    let tangent: std::collections::HashMap<PanelVertex, DVec3> = (0..n_out)
        .map(|k| {
            let (prev, next) = (panel.outline[(k + n_out - 1) % n_out], panel.outline[(k + 1) % n_out]);
            (panel.outline[k], panel.positions[next] - panel.positions[prev])
        })
        .collect();
    let along_grain = |apex: PanelVertex, mouth: PanelVertex| -> bool {
        let Some(g) = guides.grain.and_then(|g| g.try_normalize()) else { return true };
        let d = panel.positions[mouth] - panel.positions[apex];
        let across = tangent.get(&mouth).is_some_and(|t| t.dot(g).abs() <= sin_max * t.length());
        across && d.dot(g).abs() >= cos_max * d.length()
    };
    let interior = |v: PanelVertex| !on_outline.contains(&v) && !is_node(v) && !on_dart.contains(&v);
    let reflect = guides.mirror.map(|(n, d)| move |p: DVec3| p - 2.0 * (n.dot(p) - d) * n);
    let nearest = |q: DVec3, ok: &dyn Fn(PanelVertex) -> bool| -> Option<PanelVertex> {
        panel
            .positions
            .iter_enumerated()
            .filter(|(v, _)| ok(*v))
            .min_by(|a, b| a.1.distance(q).total_cmp(&b.1.distance(q)).then(a.0.cmp(&b.0)))
            .map(|(v, _)| v)
    };
    // an apex within its longest edge of the mirror plane: its dart is its own image
    let on_plane = |v: PanelVertex| {
        let reach = adjacency[v].iter().map(|&w| panel.positions[v].distance(panel.positions[w])).fold(0.0, f64::max);
        guides.mirror.is_some_and(|(n, d)| (n.dot(panel.positions[v]) - d).abs() <= reach)
    };
    let mut taken: HashSet<PanelVertex> = HashSet::new();
    let mut paths = Vec::new();
    for apex in order {
        if paths.len() >= opts.candidates {
            break;
        }
        if taken.contains(&apex) {
            continue;
        }
        let mouth_ok = |m: PanelVertex| along_grain(apex, m);
        let Some(path) = shortest_to_outline(panel, &adjacency, apex, &on_outline, &on_dart, &is_node, &mouth_ok)
        else {
            continue;
        };
        let mut chains = vec![path];
        if let Some(reflect) = reflect {
            // the mirror image: from the interior vertex nearest the apex's reflection to the
            // outline vertex nearest the mouth's; none where it would cross or touch the path
            // (a dart on the mirror plane itself stays single)
            let path = &chains[0];
            let (mouth, apex) = (path[0], path[path.len() - 1]);
            let image = nearest(reflect(panel.positions[apex]), &interior).and_then(|a| {
                let m = nearest(reflect(panel.positions[mouth]), &|v| {
                    on_outline.contains(&v) && !is_node(v) && !on_dart.contains(&v)
                })?;
                shortest_to_outline(panel, &adjacency, a, &on_outline, &on_dart, &is_node, &|v| v == m)
            });
            let near_path: HashSet<PanelVertex> =
                path.iter().flat_map(|&v| std::iter::once(v).chain(adjacency[v].iter().copied())).collect();
            match image {
                Some(image) if image.iter().all(|v| !near_path.contains(v)) => chains.push(image),
                _ if on_plane(apex) => {}
                _ => continue,
            }
        }
        for &v in chains.iter().flatten() {
            taken.insert(v);
            taken.extend(adjacency[v].iter().copied());
        }
        if chains.iter().all(|p| p.len() >= 3 && path_length(panel, p) * 1e3 >= opts.min_length_mm) {
            paths.push(chains);
        }
    }
    paths
}

/// 3D length of a path of local vertex ids, metres.
fn path_length(panel: &Panel, path: &[PanelVertex]) -> f64 {
    let points: Vec<DVec3> = path.iter().map(|&v| panel.positions[v]).collect();
    polyline_length_3d(&points)
}

/// Shortest path along edges from `apex` to an outline vertex that may open
/// (and that `mouth_ok` takes), through interior vertices that are not
/// template nodes; mouth first.
fn shortest_to_outline(
    panel: &Panel,
    adjacency: &TiSlice<PanelVertex, Vec<PanelVertex>>,
    apex: PanelVertex,
    on_outline: &HashSet<PanelVertex>,
    on_dart: &HashSet<PanelVertex>,
    is_node: &impl Fn(PanelVertex) -> bool,
    mouth_ok: &dyn Fn(PanelVertex) -> bool,
) -> Option<Vec<PanelVertex>> {
    let n = adjacency.len();
    let mut dist: TiVec<PanelVertex, f64> = TiVec::from(vec![f64::INFINITY; n]);
    let mut prev: TiVec<PanelVertex, PanelVertex> = TiVec::from(vec![apex; n]);
    dist[apex] = 0.0;
    let mut heap = BinaryHeap::from([Entry(0.0, apex)]);
    while let Some(Entry(d, u)) = heap.pop() {
        if d > dist[u] {
            continue;
        }
        if on_outline.contains(&u) {
            if !mouth_ok(u) {
                // not a mouth: a path runs inside the piece, never along its outline
                continue;
            }
            let mut path = vec![u];
            while let Some(&last) = path.last() {
                if last == apex {
                    break;
                }
                path.push(prev[last]);
            }
            return Some(path);
        }
        for &v in &adjacency[u] {
            if is_node(v) || on_dart.contains(&v) {
                continue;
            }
            let nd = d + panel.positions[u].distance(panel.positions[v]);
            if nd < dist[v] {
                dist[v] = nd;
                prev[v] = u;
                heap.push(Entry(nd, v));
            }
        }
    }
    None
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geom::mesh::VertexId;
    use crate::pattern::flatten::shapes::{cap, cylinder, faces, saddle};
    use crate::pattern::flatten::{distortion, flatten_with_seams, FlattenOptions};
    use crate::pattern::panels::disc_outline;

    fn panel((positions, triangles): (Vec<DVec3>, Vec<[u32; 3]>)) -> Panel {
        let n = positions.len();
        let global: TiVec<PanelVertex, VertexId> = (0..n).map(VertexId::from).collect();
        let triangles = faces(&triangles);
        let outline = disc_outline(&triangles, &global).expect("a disc");
        Panel {
            name: "p".into(),
            index: 0,
            global,
            unique: n,
            darts: vec![],
            positions: positions.into(),
            triangles,
            outline,
        }
    }

    fn flat(p: &Panel) -> Option<Trial> {
        let legs: Vec<Vec<PanelVertex>> = p.darts.iter().flat_map(|d| [d.a.clone(), d.b.clone()]).collect();
        let flat = flatten_with_seams(&p.positions, &p.triangles, &legs, &FlattenOptions::default()).ok()?;
        Some(Trial { distortion: distortion(&p.positions, &p.triangles, &flat.uv), flat })
    }

    fn run(p: &Panel) -> (Panel, Trial, Vec<FoundDart>) {
        let first = flat(p).expect("flattens");
        insert_darts(p, first, 0, 3e-3, &AutoDartOptions::default(), &DartGuides::default(), |q, _| flat(q))
    }

    #[test]
    fn a_developable_panel_gets_no_dart() {
        let p = panel(cylinder());
        let (out, best, found) = run(&p);
        assert!(found.is_empty());
        assert_eq!(out, p);
        assert!(best.distortion.strain_p95 < 1e-6);
    }

    #[test]
    fn a_sphere_cap_opens_darts_that_lower_the_strain() {
        // 60° aperture on a 0.3 m sphere: p95 strain ≈ 2.9 % flattened whole
        let p = panel(cap(0.3, 30.0, 24));
        let before = flat(&p).unwrap().distortion.strain_p95;
        let (out, best, found) = run(&p);
        eprintln!("cap: p95 {before:.4} → {:.4} with {} darts: {found:?}", best.distortion.strain_p95, found.len());
        assert!(before > 0.025, "{before}");
        assert!(!found.is_empty());
        assert_eq!(out.darts.len(), found.len());
        assert!(best.distortion.strain_p95 < before - 0.0005 * found.len() as f64, "{before} → {best:?}");
        assert_eq!(best.distortion.flipped, 0);
        let rim = out.rim();
        for (d, f) in out.darts.iter().zip(&found) {
            // every dart opens, its legs are sewn to equal length, and it was reported so
            let opening = dart_opening(&rim, &best.flat.uv, d).unwrap();
            assert!(opening >= 3e-3, "{}: {opening}", d.name);
            let leg = |ids: &[PanelVertex]| -> f64 {
                ids.windows(2).map(|w| best.flat.uv[w[0]].distance(best.flat.uv[w[1]])).sum()
            };
            assert!((leg(&d.a) - leg(&d.b)).abs() < 1e-6, "{}", d.name);
            assert!(f.intake_mm >= 3.0 && f.length_mm >= 20.0, "{f:?}");
            assert!(f.strain_p95_after < f.strain_p95_before);
        }
        for w in found.windows(2) {
            assert!(w[1].strain_p95_after < w[0].strain_p95_after);
        }
    }

    #[test]
    fn a_panicking_candidate_is_skipped_like_a_failing_one_and_the_rest_stay_paired() {
        // regression (issue #16): a panicking search thread's chunk came back empty and the
        // later results were paired with the wrong paths. Planted answer: candidates whose
        // newest apex has an even id panic in one run and fail (`None`) in the other; the
        // searches must agree, side by side on the pool
        let p = panel(cap(0.3, 30.0, 24));
        let even_apex = |q: &Panel| q.darts.last().and_then(|d| d.a.last()).is_some_and(|v| v.0 % 2 == 0);
        let opts = AutoDartOptions { parallel: true, ..AutoDartOptions::default() };
        let failing = insert_darts(&p, flat(&p).unwrap(), 0, 3e-3, &opts, &DartGuides::default(), |q: &Panel, _| {
            if even_apex(q) {
                None
            } else {
                flat(q)
            }
        });
        let panicking = insert_darts(&p, flat(&p).unwrap(), 0, 3e-3, &opts, &DartGuides::default(), |q: &Panel, _| {
            assert!(!even_apex(q), "planted panic");
            flat(q)
        });
        assert!(!failing.2.is_empty(), "the odd apexes still find a dart");
        assert_eq!(panicking, failing);
    }

    #[test]
    fn the_winner_is_flattened_again_to_be_kept_and_the_next_best_wins_when_that_fails() {
        // planted answer: the ranking flattening of the best first-round candidate is kept only if
        // its `Keep` flattening holds too; refusing it there must give the second best of the
        // same ranking, as if the best had not been a candidate at all
        let p = panel(cap(0.3, 30.0, 24));
        let opts = AutoDartOptions { max_darts: 1, ..AutoDartOptions::default() };
        let passes = std::sync::Mutex::new(Vec::new());
        let (_, _, best) =
            insert_darts(&p, flat(&p).unwrap(), 0, 3e-3, &opts, &DartGuides::default(), |q: &Panel, pass| {
                passes.lock().unwrap().push(pass);
                flat(q)
            });
        let passes = passes.into_inner().unwrap();
        assert_eq!(passes.iter().filter(|&&x| x == Pass::Keep).count(), 1, "one kept flattening per dart");
        assert!(passes.iter().filter(|&&x| x == Pass::Rank).count() >= 2, "a round ranks its candidates");
        let first_apex = best[0].apex;
        let refused = |q: &Panel| q.darts.last().and_then(|d| d.a.last()).map(|&v| q.positions[v]) == Some(first_apex);
        let (_, _, second) =
            insert_darts(&p, flat(&p).unwrap(), 0, 3e-3, &opts, &DartGuides::default(), |q: &Panel, pass| {
                if pass == Pass::Keep && refused(q) {
                    None
                } else {
                    flat(q)
                }
            });
        let (_, _, without) =
            insert_darts(&p, flat(&p).unwrap(), 0, 3e-3, &opts, &DartGuides::default(), |q: &Panel, _| {
                if refused(q) {
                    None
                } else {
                    flat(q)
                }
            });
        assert_eq!(second.len(), 1);
        assert_ne!(second[0].apex, first_apex);
        assert_eq!(second, without);
    }

    #[test]
    fn a_saddle_gets_no_dart_because_every_cut_would_overlap() {
        let p = panel(saddle());
        let first = flat(&p).unwrap();
        let p95 = first.distortion.strain_p95;
        let opts = AutoDartOptions { target_strain_p95: 0.0, ..AutoDartOptions::default() };
        let (out, best, found) = insert_darts(&p, first, 0, 3e-3, &opts, &DartGuides::default(), |q, _| flat(q));
        assert!(found.is_empty(), "{found:?}");
        assert_eq!(out.darts.len(), 0);
        assert_eq!(best.distortion.strain_p95, p95);
    }

    #[test]
    fn nodes_are_never_cut_through_and_disabled_means_untouched() {
        let p = panel(cap(0.3, 30.0, 24));
        let first = flat(&p).unwrap();
        // every vertex a template node: no path exists
        let (_, _, found) = insert_darts(
            &p,
            first.clone(),
            usize::MAX,
            3e-3,
            &AutoDartOptions::default(),
            &DartGuides::default(),
            |q, _| flat(q),
        );
        assert!(found.is_empty());
        let off = AutoDartOptions { enabled: false, ..AutoDartOptions::default() };
        let (out, _, found) = insert_darts(&p, first, 0, 3e-3, &off, &DartGuides::default(), |q, _| flat(q));
        assert!(found.is_empty());
        assert_eq!(out, p);
    }

    #[test]
    fn a_seam_through_a_dart_mouth_runs_in_two_pieces() {
        let mut p = panel(cap(0.3, 30.0, 12));
        let first = flat(&p).unwrap();
        let paths = candidate_paths(&p, &first.flat.uv, 0, &AutoDartOptions::default(), &DartGuides::default());
        let path = paths.first().expect("a candidate")[0].clone();
        let mouth = path[0];
        let k = p.outline.iter().position(|&v| v == mouth).unwrap();
        let n = p.outline.len();
        let seam: Vec<VertexId> = (0..5).map(|i| p.global[p.outline[(k + n - 2 + i) % n]]).collect();
        assert_eq!(p.seam_runs(&seam).unwrap().len(), 1);
        p.add_dart("d", &path).unwrap();
        let runs = p.seam_runs(&seam).unwrap();
        assert_eq!(runs.len(), 2, "{runs:?}");
        assert_eq!(runs[0].len() + runs[1].len(), 6);
        // one run ends on the mouth, the other starts on its copy
        let copies = [p.darts[0].a[0], p.darts[0].b[0]];
        assert!(copies.contains(&runs[0][runs[0].len() - 1]) && copies.contains(&runs[1][0]));
        assert_ne!(runs[0][runs[0].len() - 1], runs[1][0]);
    }

    /// The direction of a candidate's first chain, apex → mouth.
    fn direction(p: &Panel, chain: &[PanelVertex]) -> DVec3 {
        p.positions[chain[0]] - p.positions[chain[chain.len() - 1]]
    }

    #[test]
    fn darts_run_with_the_grain_and_open_across_it() {
        // planted: grain along x; every candidate runs within 30° of it and opens where the rim
        // runs across it; without a grain some candidate runs across x (the contrast)
        let p = panel(cap(0.3, 30.0, 24));
        let first = flat(&p).unwrap();
        let opts = AutoDartOptions::default();
        let cos = opts.max_grain_angle_deg.to_radians().cos();
        let guides = DartGuides { grain: Some(DVec3::X), ..Default::default() };
        let along = candidate_paths(&p, &first.flat.uv, 0, &opts, &guides);
        assert!(!along.is_empty());
        let n = p.outline.len();
        for c in &along {
            let d = direction(&p, &c[0]);
            assert!(d.x.abs() >= cos * d.length(), "{d}");
            let k = p.outline.iter().position(|&v| v == c[0][0]).unwrap();
            let t = p.positions[p.outline[(k + 1) % n]] - p.positions[p.outline[(k + n - 1) % n]];
            assert!(t.x.abs() <= opts.max_grain_angle_deg.to_radians().sin() * t.length(), "{t}");
        }
        let any = candidate_paths(&p, &first.flat.uv, 0, &opts, &DartGuides::default());
        assert!(any.iter().any(|c| direction(&p, &c[0]).x.abs() < cos * direction(&p, &c[0]).length()));
    }

    #[test]
    fn a_symmetric_piece_gets_its_darts_in_mirrored_pairs() {
        // planted: the cap is its own mirror image across x = 0; each found dart is followed by
        // its image (apex within an edge of the reflection), the pair counting two toward the
        // cap: with room for one dart, no pair is tried
        let p = panel(cap(0.3, 30.0, 24));
        let guides = DartGuides { mirror: Some((DVec3::X, 0.0)), ..Default::default() };
        let one = AutoDartOptions { max_darts: 1, ..AutoDartOptions::default() };
        let (_, _, found) = insert_darts(&p, flat(&p).unwrap(), 0, 3e-3, &one, &guides, |q, _| flat(q));
        assert!(found.len() <= 1, "{found:?}");
        let opts = AutoDartOptions { max_darts: 2, ..AutoDartOptions::default() };
        let (out, _, found) = insert_darts(&p, flat(&p).unwrap(), 0, 3e-3, &opts, &guides, |q, _| flat(q));
        assert_eq!(found.len(), 2, "{found:?}");
        assert_eq!(out.darts.len(), 2);
        assert_eq!((found[0].origin, found[1].origin), (DartOrigin::Found, DartOrigin::Mirrored));
        let reflected = found[0].apex * DVec3::new(-1.0, 1.0, 1.0);
        assert!(found[1].apex.distance(reflected) < 0.02, "{} vs {}", found[1].apex, reflected);
        // no vertex in both chains
        let [a, b] = [&out.darts[0], &out.darts[1]];
        assert!(a.a.iter().all(|v| !b.a.contains(v) && !b.b.contains(v)));
    }

    #[test]
    fn no_dart_runs_through_the_barrier() {
        // planted: a band across the cap (|y| < 2 cm) is closed; every candidate keeps off it,
        // and without the barrier some candidate runs through it (the contrast)
        let p = panel(cap(0.3, 30.0, 24));
        let first = flat(&p).unwrap();
        let band: HashSet<PanelVertex> =
            p.positions.iter_enumerated().filter(|(_, q)| q.y.abs() < 0.02).map(|(v, _)| v).collect();
        let guides = DartGuides { barrier: band.clone(), ..Default::default() };
        let kept = candidate_paths(&p, &first.flat.uv, 0, &AutoDartOptions::default(), &guides);
        assert!(!kept.is_empty());
        assert!(kept.iter().flatten().flatten().all(|v| !band.contains(v)));
        let free = candidate_paths(&p, &first.flat.uv, 0, &AutoDartOptions::default(), &DartGuides::default());
        assert!(free.iter().flatten().flatten().any(|v| band.contains(v)));
    }
}
