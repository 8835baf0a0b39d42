//! The whole garment outside the body (issue #13; `DESIGN.md` §9, "Outside
//! the body"): the template's own vertices before refinement, and the
//! garment *surface* after it.
//!
//! **Before refinement** ([`clear_coarse`]; seed 002 §5's "outside the body"
//! constraint on garment curves). Eq. (1) places every node at a fixed offset
//! in its feature point's frame and Eq. (5) carries the profiles along; on a
//! body unlike the reference one a node or a profile point can land inside
//! the skin (at the waistband, neck, underarm). The refinement never moves
//! them (they are fixed). So each node whose signed distance to the body is
//! below `c_f` ([`ClearOptions::fixed_clearance_mm`]) goes to its closest
//! body point `q` plus `c_f` outward,
//!
//! ```text
//! p ← q + c_f · u,   u = (p − q)/|p − q| outside,  (q − p)/|p − q| inside,
//!                    the outward normal of q's triangle when p = q,
//! ```
//!
//! repeated from there (at most [`ClearOptions::max_tries`] times) where the
//! step lands inside another part of the body (under the arm, between the
//! thighs). Every profile then follows its end nodes by Eq. (5)
//! ([`Profile::relocated`]), its interior points are moved out the same way,
//! and its spline is solved again through them. `c_f` is small (1 mm) so
//! that the eased girths the template declares are not widened where the
//! draft already sits close: a waistband is snug by design.
//!
//! **After refinement** ([`clear_surface`]). Vertices 3 mm outside still let
//! a convex part of the body (a hip bone, a knee, a shoulder) pass between
//! them: triangles of 2–3 cm edges chord through it. Each round finds every
//! garment triangle that crosses a body triangle by the exact test
//! ([`crate::geom::intersect::intersecting_pairs`]) and lifts its three
//! vertices along the garment's vertex normal by
//!
//! ```text
//! lift = σ min(h_σ + c, ℓ_max),   h_σ = max(0, max over the crossed body triangle's corners v of σ (v − a)·n_g)
//! σ = sign(n_b · n_g)                    (the garment triangle crosses body triangles facing one way)
//! σ = +1 if h_+ ≤ h_−, else −1            (it crosses some facing each way: a crease)
//! ```
//!
//! (`n_g` the garment triangle's outward unit normal — outside a crease,
//! where it turns against the mean `n̄` of its corners' vertex normals
//! (along which they are lifted) and the crossed body triangle faces along
//! `n̄`, that mean: where the surface folds over the part it wraps, a
//! triangle's own normal turns inward, and taken as pressed from outside
//! such a triangle was lifted inward round after round, the fold travelling
//! up the A-line's side waist on ASTM size 12, 26 pairs left after 12
//! rounds, measured; `n̄` for every folded triangle left 10–12 pairs beside
//! pop04's pressed thighs, outside the contact —, `n_b` the body
//! triangle's, `a` one of the garment triangle's corners, `c`
//! [`ClearOptions::lift_clearance_mm`], `ℓ_max` [`ClearOptions::max_lift_mm`]):
//! the height by which the body pokes out through the garment's plane (or
//! reaches under it), plus the clearance. `σ = +1` for the body part the
//! garment wraps (it faces the way the garment does); `σ = −1` for another
//! part pressing on the garment from outside (an arm on a bodice's
//! armhole), from which the garment gives way inward. A triangle that
//! crosses body triangles facing both ways spans a crease (the fold below a
//! buttock: pushed out by the buttock and in by the thigh, it oscillated,
//! 8–16 pairs left after 12 rounds on heavy short men) and moves the
//! shorter way clear of each.
//! A vertex shared by several such triangles takes the largest lift; the
//! lift then fades out over [`ClearOptions::falloff_rings`] rings of
//! neighbours (each ring half the mean of the one inside it), so the garment
//! rises in a smooth bump rather than a spike that the flattening would
//! have to stretch. Lifted
//! vertices that land inside another body part are settled by the exact
//! inside test. Rounds repeat until no pair is left or
//! [`ClearOptions::max_rounds`] is reached; the report says how many pairs
//! remain, and how many of them lie at the body's thigh contact, where no
//! two-legged garment can pass between the legs outside the body
//! ([`crate::body::contact`]); the tests require none elsewhere.
//!
//! The pattern is cut from the surface before this lifting
//! ([`ClearOptions::pattern_before_lift`]): a lift is a bump of a few
//! millimetres that cloth drapes over, and cut into a pattern piece it is an
//! undevelopable spike.
//!
//! **Failure modes**: a profile that cannot be solved again after its points
//! moved ([`ProfileError`], named by edge in [`ClearError`]). No other: a
//! vertex that cannot be moved out in `max_tries` steps stays where the last
//! step left it and is counted by the report's measurements.

use std::collections::BTreeMap;

use glam::DVec3;
use serde::{Deserialize, Serialize};

use crate::body::contact::ThighContact;
use typed_index_collections::{TiSlice, TiVec};

use crate::geom::intersect::{count_pairs, intersecting_pairs};
use crate::geom::mesh::{FaceId, VertexId};
use crate::geom::winding::{InsideMemo, WindingTree};
use crate::template::codec::CoarseMesh;
use crate::template::profile::{Profile, ProfileError};

/// Knobs of keeping the garment outside.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct ClearOptions {
    /// Least distance from the skin kept by template nodes, profile points
    /// and the other fixed vertices, mm. Default 1 (cloth thickness: the
    /// draft's own eased placement decides the rest).
    pub fixed_clearance_mm: f64,
    /// Steps of one vertex's move before giving up on it (another body part
    /// in the way), count. Default 4.
    pub max_tries: usize,
    /// Rounds of lifting intersecting triangles, count. Default 12 (garments
    /// clear in 1–3 where the body leaves room; where it leaves none — thighs
    /// pressed into each other, knees spread wider than a straight skirt's
    /// hem — more rounds only move the cloth further: 40 rounds moved a skirt
    /// 235 mm and left more pairs than 12).
    pub max_rounds: usize,
    /// Distance a lifted triangle is placed beyond the body point that
    /// crossed it, mm. Default 0.5 (the test is exact: this only keeps the
    /// cloth off the skin; a full clearance makes taller bumps, and bumps
    /// strain the flattening).
    pub lift_clearance_mm: f64,
    /// Largest lift of one vertex in one round, mm. Default 10.
    pub max_lift_mm: f64,
    /// Rings of neighbours over which a lift fades out, each ring taking
    /// [`ClearOptions::falloff`] of the mean of the ring inside it, count.
    /// Default 3 (a smooth bump, not a spike: spikes strain the flattening).
    pub falloff_rings: usize,
    /// Share of a lift passed on to the next ring. Default 0.5.
    pub falloff: f64,
    /// Cut the pattern from the surface before the lifting; the 3D garment
    /// is the lifted one. Default true: the lifts are local bumps of a few
    /// millimetres over the body's convexities (the report gives the largest),
    /// which cloth drapes over; cut into the pattern they are undevelopable
    /// spikes (trouser pieces above p95 strain 3 % over the fixtures: 9 of 80
    /// cut after the lifting, 1 before).
    pub pattern_before_lift: bool,
}

impl Default for ClearOptions {
    fn default() -> Self {
        Self {
            fixed_clearance_mm: 1.0,
            max_tries: 4,
            max_rounds: 12,
            lift_clearance_mm: 0.5,
            max_lift_mm: 10.0,
            falloff_rings: 3,
            falloff: 0.5,
            pattern_before_lift: true,
        }
    }
}

/// Why clearing failed.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum ClearError {
    /// An edge's profile could not be solved again after clearing.
    #[error("edge {edge}: profile after clearing the body: {source}")]
    Profile {
        /// The template edge.
        edge: u32,
        /// The cause.
        source: ProfileError,
    },
}

/// What [`clear_coarse`] moved.
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize, utoipa::ToSchema)]
pub struct CoarseClearReport {
    /// Template nodes moved out.
    pub nodes_moved: usize,
    /// Profile points moved out (interior points; end points are nodes).
    pub profile_points_moved: usize,
    /// Deepest node or profile point inside the body before, mm (0 if none).
    pub deepest_before_mm: f64,
}

/// What [`clear_surface`] did.
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize, utoipa::ToSchema)]
pub struct SurfaceClearReport {
    /// Garment triangles in the test.
    pub garment_triangles: usize,
    /// Intersecting garment/body triangle pairs before lifting.
    pub pairs_before: usize,
    /// Garment triangles among them.
    pub triangles_before: usize,
    /// Lifting rounds run.
    pub rounds: usize,
    /// Vertex lifts made (a vertex lifted in two rounds counts twice).
    pub lifts: usize,
    /// Intersecting pairs left after the last round.
    pub pairs_after: usize,
    /// Those of them whose body or garment triangle reaches the body's thigh
    /// contact ([`ThighContact::reaches`]), where no garment can pass between the
    /// legs outside the body ([`crate::body::contact`]): unavoidable.
    pub pairs_after_at_thigh_contact: usize,
    /// Vertices that moved.
    pub vertices_moved: usize,
    /// Largest distance a vertex moved, mm.
    pub max_moved_mm: f64,
}

/// Moves `p` out of the body to `clearance` (m) from it, if it is inside or
/// nearer (module docs). Returns the signed depth before (m, positive inside)
/// when it moved.
pub fn push_out(tree: &WindingTree, p: &mut DVec3, clearance: f64, tries: usize) -> Option<f64> {
    let (q, normal, d) = tree.closest_point_normal(*p);
    let inside = tree.is_inside(*p);
    if !inside && d >= clearance {
        return None;
    }
    let before = if inside { d } else { -d };
    let (mut q, mut normal, mut d, mut inside) = (q, normal, d, inside);
    for _ in 0..tries.max(1) {
        let u = if d > 1e-12 && d.is_finite() {
            if inside {
                (q - *p) / d
            } else {
                (*p - q) / d
            }
        } else {
            normal
        };
        if u == DVec3::ZERO {
            break;
        }
        *p = q + u * clearance;
        (q, normal, d) = tree.closest_point_normal(*p);
        inside = tree.is_inside(*p);
        // a closest point on another part means the step went too far: stop when clear
        if !inside && d >= clearance * (1.0 - 1e-6) {
            break;
        }
    }
    Some(before)
}

/// Moves the nodes and profile points of a decoded template out of the body
/// (module docs). `m` is changed in place.
///
/// # Errors
/// [`ClearError::Profile`] naming the edge whose profile could not be solved again.
pub fn clear_coarse(
    m: &mut CoarseMesh,
    edges: &[(u32, u32)],
    tree: &WindingTree,
    opts: &ClearOptions,
) -> Result<CoarseClearReport, ClearError> {
    let c = opts.fixed_clearance_mm * 1e-3;
    let mut report = CoarseClearReport::default();
    let mut moved = vec![false; m.positions.len()];
    for (p, mv) in m.positions.iter_mut().zip(&mut moved) {
        if let Some(depth) = push_out(tree, p, c, opts.max_tries) {
            report.nodes_moved += 1;
            report.deepest_before_mm = report.deepest_before_mm.max(depth * 1e3);
            *mv = true;
        }
    }
    for (i, (profile, &(s, e))) in m.profiles.iter_mut().zip(edges).enumerate() {
        let Some(pr) = profile else { continue };
        let edge = i as u32;
        let (ps, pe) = (m.positions[s as usize], m.positions[e as usize]);
        let mut changed = false;
        let mut points: Vec<DVec3> = if moved[s as usize] || moved[e as usize] {
            changed = true;
            pr.relocated(ps, pe).map_err(|source| ClearError::Profile { edge, source })?.points().to_vec()
        } else {
            pr.points().to_vec()
        };
        let last = points.len().saturating_sub(1);
        for q in points.iter_mut().take(last).skip(1) {
            if let Some(depth) = push_out(tree, q, c, opts.max_tries) {
                report.profile_points_moved += 1;
                report.deepest_before_mm = report.deepest_before_mm.max(depth * 1e3);
                changed = true;
            }
        }
        if changed {
            *pr = Profile::new(points).map_err(|source| ClearError::Profile { edge, source })?;
        }
    }
    Ok(report)
}

/// Area-weighted vertex normals of a triangle list (zero for isolated vertices).
fn vertex_normals(
    positions: &TiSlice<VertexId, DVec3>,
    triangles: &TiSlice<FaceId, [VertexId; 3]>,
) -> TiVec<VertexId, DVec3> {
    let mut n: TiVec<VertexId, DVec3> = TiVec::from(vec![DVec3::ZERO; positions.len()]);
    for t in triangles {
        let [a, b, c] = t.map(|v| positions[v]);
        let w = (b - a).cross(c - a);
        for &v in t {
            n[v] += w;
        }
    }
    n.iter().map(|v| v.normalize_or_zero()).collect()
}

/// The one-ring neighbours of every vertex, sorted.
fn neighbours(n: usize, triangles: &TiSlice<FaceId, [VertexId; 3]>) -> TiVec<VertexId, Vec<VertexId>> {
    let mut ring: TiVec<VertexId, Vec<VertexId>> = TiVec::from(vec![Vec::new(); n]);
    for t in triangles {
        for k in 0..3 {
            ring[t[k]].push(t[(k + 1) % 3]);
            ring[t[k]].push(t[(k + 2) % 3]);
        }
    }
    for r in &mut ring {
        r.sort_unstable();
        r.dedup();
    }
    ring
}

/// Spreads the lifts `need` over `rings` rings of neighbours: a vertex with
/// no lift of its own takes `share` × the mean lift of its neighbours that
/// have one (signed), ring by ring outward; lifted vertices keep theirs.
fn fade(need: &mut TiSlice<VertexId, f64>, ring: &TiSlice<VertexId, Vec<VertexId>>, rings: usize, share: f64) {
    for _ in 0..rings {
        let before = need.to_owned();
        for (i, r) in ring.iter_enumerated() {
            if before[i] != 0.0 {
                continue;
            }
            let lifted: Vec<f64> = r.iter().map(|&j| before[j]).filter(|&x| x != 0.0).collect();
            if !lifted.is_empty() {
                need[i] = share * lifted.iter().sum::<f64>() / lifted.len() as f64;
            }
        }
    }
}

/// Lifts garment triangles off the body until no garment triangle crosses a
/// body triangle (module docs). A lifted vertex that lands inside the body
/// is moved out to `clearance_mm` (the free vertices' clearance). The pairs
/// left at `contact`, the body's thigh contact, are counted apart. `memo`
/// keeps the inside answers ([`InsideMemo`], shared with the grade's other
/// exact passes).
pub fn clear_surface(
    tree: &WindingTree,
    positions: &mut TiSlice<VertexId, DVec3>,
    triangles: &TiSlice<FaceId, [VertexId; 3]>,
    clearance_mm: f64,
    contact: Option<&ThighContact>,
    opts: &ClearOptions,
    memo: &mut InsideMemo,
) -> SurfaceClearReport {
    let c = clearance_mm * 1e-3;
    let lc = opts.lift_clearance_mm * 1e-3;
    let max_lift = opts.max_lift_mm * 1e-3;
    let start = positions.to_owned();
    let mut report = SurfaceClearReport { garment_triangles: triangles.len(), ..Default::default() };
    let mut pairs = intersecting_pairs(tree, positions, triangles);
    (report.pairs_before, report.triangles_before) = count_pairs(&pairs);
    let mut need: TiVec<VertexId, f64> = TiVec::from(vec![0.0f64; positions.len()]);
    let ring = neighbours(positions.len(), triangles);
    while !pairs.is_empty() && report.rounds < opts.max_rounds {
        report.rounds += 1;
        need.iter_mut().for_each(|x| *x = 0.0);
        let normals = vertex_normals(positions, triangles);
        let own = |t: [VertexId; 3]| {
            let [a, b, cc] = t.map(|v| positions[v]);
            (b - a).cross(cc - a).normalize_or_zero()
        };
        // a garment triangle's outward normal outside a crease: its own, unless it turns
        // against its corners' vertex normals (the way the lift moves them), where the surface
        // folds over (taken where the crossed part faces along them, below)
        let outward = |t: [VertexId; 3]| {
            let (own, corners) = (own(t), t.iter().map(|&v| normals[v]).sum::<DVec3>().normalize_or_zero());
            if own.dot(corners) < 0.0 {
                corners
            } else {
                own
            }
        };
        // the way a crossed body triangle faces, seen along the garment normal `n`
        let facing = |pair: &crate::geom::intersect::IntersectingPair, n: DVec3| {
            let body = tree.face_corners(pair.body);
            let nb = (body[1] - body[0]).cross(body[2] - body[0]);
            if nb.dot(n) < 0.0 {
                -1i8
            } else {
                1
            }
        };
        // the way each garment triangle's crossed body triangles face: both ways, a crease
        let mut ways: BTreeMap<FaceId, (bool, bool)> = BTreeMap::new();
        for pair in &pairs {
            let w = ways.entry(pair.garment).or_default();
            if facing(pair, own(triangles[pair.garment])) < 0 {
                w.0 = true;
            } else {
                w.1 = true;
            }
        }
        for pair in &pairs {
            let tri = triangles[pair.garment];
            let crease = ways.get(&pair.garment).is_some_and(|w| w.0 && w.1);
            let own_n = own(tri);
            let n = if crease { own_n } else { outward(tri) };
            // a fold is lifted out of the part it wraps only (one that faces along its corners)
            let n = if facing(pair, n) > 0 { n } else { own_n };
            let a = positions[tri[0]];
            let body = tree.face_corners(pair.body);
            let height = |side: f64| body.iter().map(|&v| side * (v - a).dot(n)).fold(0.0f64, f64::max);
            let side = if crease {
                // pushed out by one part and in by another: the shorter way clear
                if height(-1.0) < height(1.0) {
                    -1.0
                } else {
                    1.0
                }
            } else {
                f64::from(facing(pair, n))
            };
            let h = height(side);
            let lift = side * (h + lc).min(max_lift);
            for k in tri {
                if lift.abs() > need[k].abs() {
                    need[k] = lift;
                }
            }
        }
        fade(&mut need, &ring, opts.falloff_rings, opts.falloff);
        for (i, p) in positions.iter_mut_enumerated() {
            if need[i] != 0.0 {
                *p += normals[i] * need[i];
                report.lifts += 1;
                if memo.is_inside(tree, *p) {
                    push_out(tree, p, c, opts.max_tries);
                }
            }
        }
        pairs = intersecting_pairs(tree, positions, triangles);
    }
    report.pairs_after = pairs.len();
    report.pairs_after_at_thigh_contact = contact.map_or(0, |c| {
        let garment = |p: &crate::geom::intersect::IntersectingPair| triangles[p.garment].map(|v| positions[v]);
        pairs.iter().filter(|p| c.reaches(&tree.face_corners(p.body)) || c.reaches(&garment(p))).count()
    });
    for (p, q) in positions.iter().zip(&start) {
        let d = p.distance(*q) * 1e3;
        if d > 0.0 {
            report.vertices_moved += 1;
            report.max_moved_mm = report.max_moved_mm.max(d);
        }
    }
    report
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geom::mesh::TriMesh;
    use crate::geom::winding::WindingOptions;

    fn sphere(r: f64, splits: usize) -> TriMesh {
        let mut m = TriMesh::icosahedron();
        for _ in 0..splits {
            m = crate::geom::simplify::split_midpoints(&m);
        }
        m.map_positions(|p| p.normalize() * r).unwrap()
    }

    #[test]
    fn a_coarse_shell_around_a_fine_sphere_is_lifted_clear() {
        // a coarse icosahedral shell whose vertices are all 3 mm outside a fine sphere:
        // its flat faces chord through the sphere (poke-through between vertices)
        let body = sphere(0.1, 4);
        let tree = WindingTree::new(&body, &WindingOptions::default());
        let shell = sphere(0.103, 0);
        let tris: TiVec<FaceId, [VertexId; 3]> = shell.triangles().to_vec().into();
        let mut pos: TiVec<VertexId, DVec3> = shell.positions().to_vec().into();
        assert!(pos.iter().all(|p| !tree.is_inside(*p)));
        let report =
            clear_surface(&tree, &mut pos, &tris, 3.0, None, &ClearOptions::default(), &mut InsideMemo::default());
        assert!(report.pairs_before > 0, "{report:?}");
        assert_eq!(report.triangles_before, 20, "every face of the shell chords through: {report:?}");
        assert_eq!(report.pairs_after, 0, "{report:?}");
        assert!(intersecting_pairs(&tree, &pos, &tris).is_empty());
        // the icosahedron's inradius must reach the sphere: ≥ 0.1 m / 0.7947 (inradius/circumradius)
        let inradius = pos.raw[0].length() * 0.794_654_5;
        assert!(inradius >= 0.1, "inradius {inradius}");
        // lifted evenly: every vertex moved the same amount along its normal (symmetry)
        let r: Vec<f64> = pos.iter().map(|p| p.length()).collect();
        let spread = r.iter().cloned().fold(f64::MIN, f64::max) - r.iter().cloned().fold(f64::MAX, f64::min);
        assert!(spread < 1e-9, "spread {spread}");
    }

    #[test]
    fn nodes_and_profile_points_inside_are_moved_out_to_the_fixed_clearance() {
        let body = sphere(0.1, 4);
        let tree = WindingTree::new(&body, &WindingOptions::default());
        // two nodes: one 5 mm inside, one 20 mm outside, with an arc profile dipping inside
        let a = DVec3::new(0.095, 0.0, 0.0);
        let b = DVec3::new(0.0, 0.12, 0.0);
        let arc: Vec<DVec3> =
            (0..=6).map(|k| a.lerp(b, k as f64 / 6.0).normalize() * (0.09 + 0.03 * k as f64 / 6.0)).collect();
        let mut arc = arc;
        arc[0] = a;
        arc[6] = b;
        let mut m = CoarseMesh {
            positions: vec![a, b, DVec3::new(0.0, 0.0, 0.2)],
            triangles: vec![[0, 1, 2]],
            profiles: vec![Some(Profile::new(arc).unwrap()), None, None],
            hung: vec![],
        };
        let edges = [(0, 1), (1, 2), (2, 0)];
        let report = clear_coarse(&mut m, &edges, &tree, &ClearOptions::default()).unwrap();
        assert_eq!(report.nodes_moved, 1, "{report:?}");
        assert!(report.profile_points_moved >= 1, "{report:?}");
        assert!((report.deepest_before_mm - 5.0).abs() < 0.5, "{report:?}");
        let d = |p: DVec3| -tree.signed_depth(p);
        assert!((d(m.positions[0]) - 1e-3).abs() < 1e-6, "node at {} mm", d(m.positions[0]) * 1e3);
        assert_eq!(m.positions[1], b, "the outside node stays");
        let pr = m.profiles[0].as_ref().unwrap();
        assert_eq!(pr.start(), m.positions[0]);
        assert_eq!(pr.end(), b);
        for q in pr.points() {
            assert!(d(*q) >= 1e-3 - 1e-6, "profile point {} mm from the skin", d(*q) * 1e3);
        }
    }
}
