//! Sketch edits of a template (seed 000 §4; issue #18 item 3, the geometry:
//! [`super::edit`] applies one to a template under seed 002's constraints,
//! the service's `POST /v1/templates/{name}/edits` stores it): a stroke
//! drawn in one of the canonical orthographic views moves a node (§4.2,
//! Eq. (4)) or re-profiles the edges it runs along (§4.3, Eqs. (6)–(7) and
//! the K(v) rules).
//!
//! # Views
//!
//! A [`SketchView`] is one of the four canonical orthographic views
//! (front, back, left, right; `+y` up on screen) with a scale `λ` in metres
//! per pixel and the pixel where the world origin lands. Screen `x` runs
//! right, screen `y` down: `ζ(p) = o + ((p·r)/λ, −(p·w)/λ)` with `r` the
//! view's right axis and `w` the world up. A pixel lifts to the line
//! `r (x − oₓ) λ + w (o_y − y) λ + t d`, `d` the axis towards the viewer.
//!
//! # Move node (§4.2, Eq. (4), sign kept: `seeds-notes.md` §A.4)
//!
//! The direction stroke `Φ*` gives `Δ = φ*_n − φ*_1` (pixels). Each world
//! axis `n_τ` has a screen image `a_τ` (pixels per metre); the node moves
//! along the axis whose image is most nearly parallel to `Δ`,
//! `τ = argmax |cos∠(Δ, a_τ)|` (both directions of an axis count), by
//! `s = (Δ·a_τ) / |a_τ|²`: `p* = p + s n_τ`. For an axis in the screen
//! plane `|a_τ| = 1/λ` and `s = λ (Δ·â_τ)`, the paper's `λ |(φ*_n φ*_1)_τ|`
//! with its sign kept (as printed, the absolute value could only move a
//! node towards `+τ`).
//!
//! # Profile from a stroke (§4.3)
//!
//! 1. An edge `v_l v_m` is selected iff both its nodes are visible and
//!    within `ε` pixels of the stroke polyline ([`SketchOptions::epsilon_px`],
//!    the paper's 4).
//! 2. The stroke is lifted onto a plane: the least-squares plane of the
//!    selected edges' nodes ([`Plane::fit`]); where they are collinear (one edge, or a
//!    straight chain) the plane through the edge that bisects the dihedral
//!    angle of its faces, normal `(n₁ + n₂)/|n₁ + n₂|` (one face: its own
//!    normal), "so that the sketched profile faces towards the camera as
//!    much as possible".
//! 3. Per selected edge, `ψ*_l` and `ψ*_m` are the lifted stroke points
//!    nearest its nodes and `ψ*_{l..m}` its new points (reversed when the
//!    stroke runs from `v_m` to `v_l`).
//! 4. K(v) rules, `K(v)` the number of selected edges at `v`: a node with
//!    `K = 1` (an end of the sketched chain) stays and the points are warped
//!    onto it by Eq. (6); a node with `K > 1` (the stroke runs through it)
//!    moves onto its stroke point.
//! 5. **Eq. (6)** with the parameters of **Eq. (7)** (the printed lower
//!    limit `j = 1 + 1` read `l + 1`, so `u_m = 1`):
//!
//! ```text
//! p*(ψ_j) = (|v_l v_m| / |ψ_l ψ_m|) · {p(ψ_j) − p(ψ_l) − u_j [p(ψ_m) − p(ψ_l)]} + p(v_l) + u_j [p(v_m) − p(v_l)]
//! u_l = 0,  u_j = u_{j−1} + |ψ_j − ψ_{j−1}| / Σ_{k=l+1..m} |ψ_k − ψ_{k−1}|
//! ```
//!
//! # Failure modes
//!
//! [`SketchError`]: a stroke with too few points or a non-finite point, a
//! scale `λ` that is not positive and finite, no edge within `ε`, a
//! direction stroke of zero length, a node or edge index out of range, a
//! lifted stroke that misses the plane (a plane seen edge-on).

use glam::{DVec2, DVec3};
use serde::{Deserialize, Serialize};

use crate::geom::plane::Plane;
use crate::geom::polyline::point_segment;

/// The canonical orthographic views (module docs).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, utoipa::ToSchema)]
#[serde(rename_all = "snake_case")]
pub enum CanonicalView {
    /// Looking at the body's front (along `−z`; `+x`, the body's left, on screen right).
    Front,
    /// Looking at its back (along `+z`).
    Back,
    /// Looking at its left side (along `−x`).
    Left,
    /// Looking at its right side (along `+x`).
    Right,
}

impl CanonicalView {
    /// `(r, d)`: the screen's right axis and the axis towards the viewer.
    pub fn axes(self) -> (DVec3, DVec3) {
        match self {
            CanonicalView::Front => (DVec3::X, DVec3::Z),
            CanonicalView::Back => (DVec3::NEG_X, DVec3::NEG_Z),
            CanonicalView::Left => (DVec3::NEG_Z, DVec3::X),
            CanonicalView::Right => (DVec3::Z, DVec3::NEG_X),
        }
    }
}

/// A view to sketch in (module docs).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize, utoipa::ToSchema)]
#[serde(deny_unknown_fields)]
pub struct SketchView {
    /// Which view.
    pub view: CanonicalView,
    /// Metres per pixel, `λ`.
    pub metres_per_px: f64,
    /// The pixel where the world origin lands, `o`.
    pub origin_px: [f64; 2],
}

impl SketchView {
    /// `ζ(p)`: the pixel of world point `p`.
    pub fn to_px(&self, p: DVec3) -> DVec2 {
        let (r, _) = self.view.axes();
        DVec2::new(self.origin_px[0] + p.dot(r) / self.metres_per_px, self.origin_px[1] - p.y / self.metres_per_px)
    }

    /// The world line of pixel `q`: a point on it (depth 0) and its direction (towards the viewer).
    pub fn ray(&self, q: DVec2) -> (DVec3, DVec3) {
        let (r, d) = self.view.axes();
        let l = self.metres_per_px;
        (r * ((q.x - self.origin_px[0]) * l) + DVec3::Y * ((self.origin_px[1] - q.y) * l), d)
    }

    fn check(&self) -> Result<(), SketchError> {
        let ok =
            self.metres_per_px.is_finite() && self.metres_per_px > 0.0 && self.origin_px.iter().all(|c| c.is_finite());
        if ok {
            Ok(())
        } else {
            Err(SketchError::View { metres_per_px: self.metres_per_px })
        }
    }
}

/// Knobs of the sketch edits.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize, utoipa::ToSchema)]
#[serde(default, deny_unknown_fields)]
pub struct SketchOptions {
    /// An edge is selected when both its nodes lie within this many pixels
    /// of the stroke, `ε`. Default 4 (seed 000 §4.3).
    pub epsilon_px: f64,
}

impl Default for SketchOptions {
    fn default() -> Self {
        Self { epsilon_px: 4.0 }
    }
}

/// Why a sketch edit was refused.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum SketchError {
    /// The view's scale is not a positive finite number (or its origin is not finite).
    #[error("the view's scale {metres_per_px} m/px is not a positive finite number, or its origin is not finite")]
    View {
        /// The scale given.
        metres_per_px: f64,
    },
    /// A stroke needs `min` points.
    #[error("the stroke has {points} points; at least {min} are needed")]
    ShortStroke {
        /// Points given.
        points: usize,
        /// Least.
        min: usize,
    },
    /// A stroke point is not finite.
    #[error("stroke point {index} is not finite")]
    NonFinite {
        /// Its index.
        index: usize,
    },
    /// The direction stroke starts where it ends.
    #[error("the direction stroke has no length")]
    NoDirection,
    /// No edge has both nodes visible and within `ε` of the stroke.
    #[error("no visible edge has both nodes within {epsilon_px} px of the stroke")]
    NothingSelected {
        /// The tolerance.
        epsilon_px: f64,
    },
    /// An index beyond the nodes.
    #[error("edge {edge} names node {node}, beyond the {nodes} nodes")]
    Index {
        /// The edge (or face) index.
        edge: usize,
        /// The node named.
        node: u32,
        /// How many nodes there are.
        nodes: usize,
    },
    /// The projection plane is seen edge-on: the stroke cannot be lifted onto it.
    #[error("the projection plane is seen edge-on in this view; sketch in another view")]
    EdgeOn,
}

/// Where a node-move stroke sends the node (§4.2).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct NodeMove {
    /// The axis moved along: 0 `x`, 1 `y`, 2 `z`.
    pub axis: usize,
    /// Signed distance along it, m.
    pub distance_m: f64,
    /// The node's new position.
    pub position: DVec3,
}

/// Eq. (4) with the sign kept (module docs): the move of a node at `p` by the
/// direction stroke `stroke` (pixels, at least two points) in `view`.
///
/// # Errors
/// [`SketchError::View`], [`SketchError::ShortStroke`], [`SketchError::NonFinite`],
/// [`SketchError::NoDirection`].
pub fn move_node(p: DVec3, stroke: &[DVec2], view: &SketchView) -> Result<NodeMove, SketchError> {
    view.check()?;
    check_stroke(stroke, 2)?;
    let delta = stroke[stroke.len() - 1] - stroke[0];
    if delta.length_squared() == 0.0 {
        return Err(SketchError::NoDirection);
    }
    // each axis's screen image, pixels per metre: ζ(p + n) − ζ(p)
    let images = [DVec3::X, DVec3::Y, DVec3::Z].map(|n| view.to_px(n) - view.to_px(DVec3::ZERO));
    let cos =
        |a: DVec2| if a.length_squared() > 0.0 { (delta.dot(a) / (delta.length() * a.length())).abs() } else { -1.0 };
    // the most probable axis, the first on ties
    let axis = (0..3).fold(0, |best, k| if cos(images[k]) > cos(images[best]) { k } else { best });
    let a = images[axis];
    let s = delta.dot(a) / a.length_squared();
    let n = [DVec3::X, DVec3::Y, DVec3::Z][axis];
    Ok(NodeMove { axis, distance_m: s, position: p + n * s })
}

fn check_stroke(stroke: &[DVec2], min: usize) -> Result<(), SketchError> {
    if stroke.len() < min {
        return Err(SketchError::ShortStroke { points: stroke.len(), min });
    }
    match stroke.iter().position(|q| !q.is_finite()) {
        Some(index) => Err(SketchError::NonFinite { index }),
        None => Ok(()),
    }
}

/// Distance in pixels from `q` to the stroke polyline.
fn distance_to_stroke(q: DVec2, stroke: &[DVec2]) -> f64 {
    if stroke.len() == 1 {
        return q.distance(stroke[0]);
    }
    let at = |a: DVec2, b: DVec2| a.lerp(b, point_segment(q.extend(0.0), a.extend(0.0), b.extend(0.0)));
    stroke.windows(2).map(|w| q.distance(at(w[0], w[1]))).fold(f64::INFINITY, f64::min)
}

/// §4.3 step 1: the edges (indices into `edges`) whose two nodes are
/// `visible` and within `ε` pixels of `stroke` in `view`.
///
/// # Errors
/// [`SketchError::Index`] for an edge naming a node beyond `nodes`; the
/// view and stroke errors of [`move_node`].
pub fn select_edges(
    nodes: &[DVec3],
    visible: &[bool],
    edges: &[[u32; 2]],
    stroke: &[DVec2],
    view: &SketchView,
    opts: &SketchOptions,
) -> Result<Vec<usize>, SketchError> {
    view.check()?;
    check_stroke(stroke, 2)?;
    let mut out = Vec::new();
    for (k, e) in edges.iter().enumerate() {
        for &v in e {
            if v as usize >= nodes.len() {
                return Err(SketchError::Index { edge: k, node: v, nodes: nodes.len() });
            }
        }
        let near = |v: u32| {
            visible.get(v as usize).copied().unwrap_or(false)
                && distance_to_stroke(view.to_px(nodes[v as usize]), stroke) < opts.epsilon_px
        };
        if near(e[0]) && near(e[1]) {
            out.push(k);
        }
    }
    Ok(out)
}

/// §4.3 step 2 for collinear nodes: the plane through edge `[a, b]` that
/// bisects the dihedral angle of its faces (`faces`: node triples,
/// counter-clockwise seen from outside), normal `(n₁ + n₂)/|n₁ + n₂|`; with
/// one face its normal; `None` with none, or when the normals cancel.
pub fn dihedral_bisector(nodes: &[DVec3], faces: &[[u32; 3]], [a, b]: [u32; 2]) -> Option<Plane> {
    let normal_sum: DVec3 = faces
        .iter()
        .filter(|f| f.contains(&a) && f.contains(&b))
        .filter_map(|f| {
            let [p, q, r] = f.map(|v| nodes.get(v as usize).copied());
            Some((q? - p?).cross(r? - p?).normalize_or_zero())
        })
        .sum();
    let normal = normal_sum.try_normalize()?;
    let point = *nodes.get(a as usize)?;
    // the edge lies in the plane: remove any component of the normal along it
    let along = (*nodes.get(b as usize)? - point).normalize_or_zero();
    Plane::from_point_normal(point, normal - along * normal.dot(along))
}

/// Lifts pixel `q` of `view` onto `plane` along the view ray (§4.3 step 3).
fn lift(q: DVec2, view: &SketchView, plane: &Plane) -> Option<DVec3> {
    let (o, d) = view.ray(q);
    let den = d.dot(plane.normal);
    if den.abs() < 1e-12 {
        return None;
    }
    Some(o - d * (plane.signed_distance(o) / den))
}

/// Eq. (6) with Eq. (7)'s parameters: the points `psi` (from `ψ_l` to
/// `ψ_m`) warped so that they run from `from` to `to` exactly (module docs).
/// Fewer than two points, or `ψ_l = ψ_m`, give the straight chord's ends.
pub fn warp_onto(psi: &[DVec3], from: DVec3, to: DVec3) -> Vec<DVec3> {
    let n = psi.len();
    if n < 2 {
        return vec![from, to];
    }
    let total: f64 = psi.windows(2).map(|w| w[0].distance(w[1])).sum();
    let (pl, pm) = (psi[0], psi[n - 1]);
    let chord = pl.distance(pm);
    if total <= 0.0 || chord <= 0.0 {
        return vec![from, to];
    }
    let ratio = from.distance(to) / chord;
    let mut u = 0.0;
    let mut out = Vec::with_capacity(n);
    for j in 0..n {
        if j > 0 {
            u += psi[j].distance(psi[j - 1]) / total;
        }
        let uj = if j == n - 1 { 1.0 } else { u };
        out.push((psi[j] - pl - (pm - pl) * uj) * ratio + from + (to - from) * uj);
    }
    // the ends exactly on the nodes (Eq. (6) is exact there up to rounding)
    out[0] = from;
    out[n - 1] = to;
    out
}

/// What a profile stroke did (§4.3).
#[derive(Debug, Clone, PartialEq)]
pub struct ProfileEdit {
    /// The selected edges (indices into the edges given).
    pub edges: Vec<usize>,
    /// Per selected edge, its new points from its first node to its second,
    /// both nodes included (at their positions after `moved`).
    pub profiles: Vec<Vec<DVec3>>,
    /// Nodes the stroke runs through (`K > 1`), moved onto it: `(node, position)`.
    pub moved: Vec<(u32, DVec3)>,
    /// The plane the stroke was lifted onto.
    pub plane: Plane,
}

/// §4.3: the profile stroke `stroke` (pixels) in `view` over the template's
/// `nodes`, `edges` (node pairs) and coarse `faces` (node triples, for the
/// dihedral bisector), `visible[v]` whether node `v` is seen.
///
/// # Errors
/// [`SketchError`]: the view and stroke errors of [`select_edges`],
/// [`SketchError::NothingSelected`], [`SketchError::EdgeOn`].
pub fn profile_stroke(
    nodes: &[DVec3],
    visible: &[bool],
    edges: &[[u32; 2]],
    faces: &[[u32; 3]],
    stroke: &[DVec2],
    view: &SketchView,
    opts: &SketchOptions,
) -> Result<ProfileEdit, SketchError> {
    let selected = select_edges(nodes, visible, edges, stroke, view, opts)?;
    let Some(&first) = selected.first() else {
        return Err(SketchError::NothingSelected { epsilon_px: opts.epsilon_px });
    };
    let mut ends: Vec<u32> = selected.iter().flat_map(|&k| edges[k]).collect();
    ends.sort_unstable();
    ends.dedup();
    let points: Vec<DVec3> = ends.iter().map(|&v| nodes[v as usize]).collect();
    let plane =
        Plane::fit(&points).or_else(|| dihedral_bisector(nodes, faces, edges[first])).ok_or(SketchError::EdgeOn)?;
    let lifted: Vec<DVec3> =
        stroke.iter().map(|&q| lift(q, view, &plane)).collect::<Option<_>>().ok_or(SketchError::EdgeOn)?;
    // K(v): selected edges at each node
    let k_of = |v: u32| selected.iter().filter(|&&k| edges[k].contains(&v)).count();
    let nearest = |p: DVec3| {
        (0..lifted.len()).fold(0, |best, j| if lifted[j].distance(p) < lifted[best].distance(p) { j } else { best })
    };
    // K > 1 nodes move onto their stroke point first
    let moved: Vec<(u32, DVec3)> =
        ends.iter().filter(|&&v| k_of(v) > 1).map(|&v| (v, lifted[nearest(nodes[v as usize])])).collect();
    let at = |v: u32| moved.iter().find(|m| m.0 == v).map_or(nodes[v as usize], |m| m.1);
    let profiles = selected
        .iter()
        .map(|&k| {
            let [a, b] = edges[k];
            let (l, m) = (nearest(nodes[a as usize]), nearest(nodes[b as usize]));
            let psi: Vec<DVec3> =
                if l <= m { lifted[l..=m].to_vec() } else { lifted[m..=l].iter().rev().copied().collect() };
            // K = 1 ends stay and the points are warped onto them (Eq. 6); K > 1 ends were moved
            // onto their stroke points, so the warp keeps those in place
            warp_onto(&psi, at(a), at(b))
        })
        .collect();
    Ok(ProfileEdit { edges: selected, profiles, moved, plane })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn front() -> SketchView {
        SketchView { view: CanonicalView::Front, metres_per_px: 0.002, origin_px: [500.0, 900.0] }
    }

    #[test]
    fn views_map_and_lift_consistently() {
        for view in [CanonicalView::Front, CanonicalView::Back, CanonicalView::Left, CanonicalView::Right] {
            let v = SketchView { view, metres_per_px: 0.0015, origin_px: [320.0, 700.0] };
            let p = DVec3::new(0.12, 1.1, -0.07);
            let (o, d) = v.ray(v.to_px(p));
            // p lies on its pixel's ray
            let off = (p - o) - d * (p - o).dot(d);
            assert!(off.length() < 1e-12, "{view:?}");
            // up is up on screen (y down)
            assert!(v.to_px(p + DVec3::Y * 0.01).y < v.to_px(p).y);
        }
        // the front view shows +x (the body's left) to the right
        assert!(front().to_px(DVec3::X * 0.1).x > front().to_px(DVec3::ZERO).x);
    }

    #[test]
    fn a_mostly_horizontal_stroke_in_the_front_view_moves_the_node_along_x_by_lambda_dx() {
        // seed 000 claim 8 (§4.2): the most probable axis, the distance λ·Δx, and the sign kept
        let p = DVec3::new(0.1, 1.0, 0.05);
        let stroke = [DVec2::new(400.0, 300.0), DVec2::new(430.0, 305.0), DVec2::new(460.0, 308.0)];
        let m = move_node(p, &stroke, &front()).unwrap();
        assert_eq!(m.axis, 0);
        assert!((m.distance_m - 0.002 * 60.0).abs() < 1e-12, "{}", m.distance_m);
        assert_eq!(m.position, p + DVec3::X * m.distance_m);
        // drawn the other way: the other way along x (the printed |·| lost this)
        let back: Vec<DVec2> = stroke.iter().rev().copied().collect();
        let m = move_node(p, &back, &front()).unwrap();
        assert!((m.distance_m + 0.12).abs() < 1e-12);
        // a mostly vertical stroke, drawn upwards on screen, moves it up
        let up = [DVec2::new(400.0, 300.0), DVec2::new(404.0, 250.0)];
        let m = move_node(p, &up, &front()).unwrap();
        assert_eq!(m.axis, 1);
        assert!((m.distance_m - 0.1).abs() < 1e-12);
        // in a side view, horizontal on screen is z
        let side = SketchView { view: CanonicalView::Right, ..front() };
        assert_eq!(move_node(p, &stroke, &side).unwrap().axis, 2);
        assert_eq!(move_node(p, &[stroke[0], stroke[0]], &front()), Err(SketchError::NoDirection));
        assert_eq!(move_node(p, &stroke[..1], &front()), Err(SketchError::ShortStroke { points: 1, min: 2 }));
    }

    #[test]
    fn epsilon_selects_an_edge_whose_nodes_are_3_px_off_the_stroke_and_not_5() {
        // seed 000 claim 4: ε = 4 px
        let view = front();
        let nodes = [DVec3::new(0.0, 1.0, 0.1), DVec3::new(0.2, 1.0, 0.1)];
        let px = nodes.map(|p| view.to_px(p));
        let stroke_at = |off: f64| vec![px[0] + DVec2::new(-20.0, off), px[1] + DVec2::new(20.0, off)];
        let o = SketchOptions::default();
        let sel = |off: f64| select_edges(&nodes, &[true, true], &[[0, 1]], &stroke_at(off), &view, &o).unwrap();
        assert_eq!(sel(3.0), vec![0]);
        assert_eq!(sel(-3.0), vec![0]);
        assert!(sel(5.0).is_empty());
        // an invisible node keeps its edge out
        assert!(select_edges(&nodes, &[true, false], &[[0, 1]], &stroke_at(0.0), &view, &o).unwrap().is_empty());
        assert_eq!(
            select_edges(&nodes, &[true, true], &[[0, 7]], &stroke_at(0.0), &view, &o),
            Err(SketchError::Index { edge: 0, node: 7, nodes: 2 })
        );
    }

    #[test]
    fn a_single_edge_stroke_lifts_onto_the_dihedral_bisector() {
        // seed 000 claim 5: one edge selected → the plane contains the edge and its normal
        // bisects the two adjacent face normals
        let nodes = [
            DVec3::new(0.0, 1.0, 0.1),
            DVec3::new(0.2, 1.0, 0.1),
            DVec3::new(0.1, 1.2, 0.05),
            DVec3::new(0.1, 0.8, 0.0),
        ];
        let faces = [[0, 1, 2], [1, 0, 3]];
        let plane = dihedral_bisector(&nodes, &faces, [0, 1]).unwrap();
        let n = |f: [u32; 3]| {
            let [p, q, r] = f.map(|v| nodes[v as usize]);
            (q - p).cross(r - p).normalize()
        };
        let (n1, n2) = (n(faces[0]), n(faces[1]));
        assert!((plane.normal.dot(n1) - plane.normal.dot(n2)).abs() < 1e-12, "bisects");
        assert!(plane.normal.dot(n1) > 0.0);
        for p in [nodes[0], nodes[1]] {
            assert!(plane.signed_distance(p).abs() < 1e-12, "contains the edge");
        }
        // and profile_stroke falls back to it: two nodes are collinear
        let view = front();
        let stroke: Vec<DVec2> = (0..=10)
            .map(|k| {
                view.to_px(nodes[0].lerp(nodes[1], k as f64 / 10.0))
                    + DVec2::new(0.0, -6.0 * (k * (10 - k)) as f64 / 25.0)
            })
            .collect();
        let edit =
            profile_stroke(&nodes, &[true; 4], &[[0, 1], [1, 2]], &faces, &stroke, &view, &SketchOptions::default())
                .unwrap();
        assert_eq!(edit.edges, vec![0]);
        assert_eq!(edit.plane, plane);
        for q in &edit.profiles[0] {
            assert!(plane.signed_distance(*q).abs() < 1e-9, "the profile lies in the plane");
        }
    }

    #[test]
    fn eq_6_puts_the_ends_on_the_nodes_keeps_a_chord_straight_and_commutes_with_scale() {
        // seed 000 claim 6 and the derived properties of §A.5
        let psi: Vec<DVec3> = (0..=8)
            .map(|k| {
                let t = k as f64 / 8.0;
                DVec3::new(t, 0.1 * (std::f64::consts::PI * t).sin(), 0.02 * t * t)
            })
            .collect();
        let (from, to) = (DVec3::new(0.3, 1.0, 0.2), DVec3::new(0.1, 1.4, 0.25));
        let w = warp_onto(&psi, from, to);
        assert_eq!((w[0], w[8]), (from, to));
        // points on the chord stay on the (new) chord
        let straight: Vec<DVec3> =
            (0..=5).map(|k| DVec3::ZERO.lerp(DVec3::new(1.0, 2.0, 0.5), k as f64 / 5.0)).collect();
        let ws = warp_onto(&straight, from, to);
        for q in &ws {
            let t = (*q - from).dot(to - from) / (to - from).length_squared();
            assert!((*q - from.lerp(to, t)).length() < 1e-12);
        }
        // uniform scale about the origin: warp(k ψ, k a, k b) = k warp(ψ, a, b)
        let k = 1.7;
        let scaled: Vec<DVec3> = psi.iter().map(|p| *p * k).collect();
        for (a, b) in warp_onto(&scaled, from * k, to * k).iter().zip(&w) {
            assert!((*a - *b * k).length() < 1e-12);
        }
    }

    #[test]
    fn a_two_edge_chain_moves_its_middle_node_onto_the_stroke_and_keeps_its_ends() {
        // seed 000 claim 7: K(middle) = 2 moves onto the stroke, K(ends) = 1 stay
        let nodes = [
            DVec3::new(0.0, 1.0, 0.1),
            DVec3::new(0.1, 1.0, 0.1),
            DVec3::new(0.2, 1.0, 0.1),
            DVec3::new(0.1, 1.2, 0.1),
        ];
        let faces = [[0, 1, 3], [1, 2, 3]];
        let view = front();
        // the stroke bulges 3 px above the middle node, 2 px at the ends
        let stroke: Vec<DVec2> = (0..=20)
            .map(|k| {
                let t = k as f64 / 20.0;
                view.to_px(nodes[0].lerp(nodes[2], t)) + DVec2::new(0.0, -2.0 - 4.0 * t * (1.0 - t))
            })
            .collect();
        let edit = profile_stroke(
            &nodes,
            &[true; 4],
            &[[0, 1], [1, 2], [1, 3]],
            &faces,
            &stroke,
            &view,
            &SketchOptions::default(),
        )
        .unwrap();
        assert_eq!(edit.edges, vec![0, 1]);
        assert_eq!(edit.moved.len(), 1);
        let (v, p) = edit.moved[0];
        assert_eq!(v, 1);
        // onto the stroke: 3 px up = 6 mm, in the nodes' plane z = 0.1
        assert!((p - DVec3::new(0.1, 1.006, 0.1)).length() < 1e-9, "{p}");
        assert_eq!(edit.profiles[0][0], nodes[0]);
        assert_eq!(*edit.profiles[0].last().unwrap(), p);
        assert_eq!(edit.profiles[1][0], p);
        assert_eq!(*edit.profiles[1].last().unwrap(), nodes[2]);
    }
}
