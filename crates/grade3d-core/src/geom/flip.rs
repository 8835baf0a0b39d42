//! Lawson's edge flips on a triangle mesh in 3D, raising its smallest
//! angles without moving or adding a vertex (issue #18: the coarse
//! template a QEM contraction leaves, seed 000 §3.3, has slivers — 24 of
//! the authored skirt's 441 faces under 5° — whose subdivision folds the
//! refined garment along their long edges).
//!
//! # Method
//!
//! Lawson (1977), the max–min angle criterion: an edge `ab` shared by the
//! triangles `abc` and `bad` is replaced by `cd` when
//!
//! ```text
//! min∠(acd, dbc) > min∠(abc, bad) + gain
//! ```
//!
//! (`min∠` the smallest interior angle of the pair). On a plane this
//! reaches the Delaunay triangulation of the vertices within the fixed
//! edges; in 3D a flip also changes the surface's shape, so an edge is
//! flipped only where the pair is nearly flat (the angle between the two
//! normals at most [`FlipOptions::max_dihedral_deg`]) and both new
//! triangles face the way the pair did (normals within 90° of the pair's
//! mean: the quad is convex seen along it). An edge is *fixed* when it is
//! not shared by exactly two triangles, when its triangles lie in
//! different regions (the caller's labels: a garment's pieces and girth
//! bands), or when the flip would make an edge the mesh already has.
//!
//! One exception to the flatness rule: an **ear on a line between
//! regions** — a triangle `abc` whose edges `bc` and `ca` are both shared
//! with triangles of other regions (a girth line between two bands), its
//! angle at `c` at least [`FlipOptions::ear_angle_deg`] — is a sliver lying
//! along that line, across the surface (the QEM contraction of seed 000
//! §3.3 leaves one where three nodes of a curved girth line close a
//! triangle: the authored A-line skirt's back hip). Its edge `ab` flips
//! whatever the dihedral angle, the new triangles checked against the
//! other triangle's normal alone.
//!
//! A **cap** — a triangle with an angle of at least
//! [`FlipOptions::cap_angle_deg`], its corners nearly on one line — has no
//! normal worth the name, so it flips the same way wherever it lies (the
//! contraction leaves fans of them along a straight seam whose nodes are
//! closer than the band's interior ones: the shift dress's side seams below
//! the hip, down to 0.08°).
//!
//! Passes run over the edges in a fixed order until one flips nothing (or
//! [`FlipOptions::max_passes`]); a triangle flipped in a pass is not
//! flipped again in that pass. The result is deterministic.
//!
//! # Preconditions and failure modes
//!
//! Triangle corners index `positions` and are consistently oriented across
//! the edges that may flip. No errors: an out-of-range corner or a
//! degenerate triangle leaves its edges fixed; the vertex set, the triangle
//! count, every fixed edge and the orientation are kept.

use std::collections::{BTreeMap, BTreeSet};

use glam::DVec3;

/// Knobs of [`lawson_flips`]; each documents its default and unit.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct FlipOptions {
    /// Largest angle between the two triangles' normals at an edge that may
    /// flip, degrees. Default 40.
    pub max_dihedral_deg: f64,
    /// Least rise of the pair's smallest angle that earns a flip, degrees.
    /// Default 0.5.
    pub min_gain_deg: f64,
    /// Most passes over the edges (count). Default 64.
    pub max_passes: usize,
    /// Least angle at the middle corner of an ear on a line between
    /// regions that flips whatever its dihedral (module docs), degrees.
    /// Default 150.
    pub ear_angle_deg: f64,
    /// Least angle at a corner that makes its triangle a *cap* (module
    /// docs), flipped like an ear wherever it lies, degrees; 180: none.
    /// Default 180.
    pub cap_angle_deg: f64,
}

impl Default for FlipOptions {
    fn default() -> Self {
        Self { max_dihedral_deg: 40.0, min_gain_deg: 0.5, max_passes: 64, ear_angle_deg: 150.0, cap_angle_deg: 180.0 }
    }
}

/// The interior angle at `c` of the triangle `c`, `a`, `b`, radians (0
/// when degenerate).
fn angle_at(c: DVec3, a: DVec3, b: DVec3) -> f64 {
    let (u, v) = (a - c, b - c);
    let d = u.length() * v.length();
    if d <= 0.0 || !d.is_finite() {
        0.0
    } else {
        (u.dot(v) / d).clamp(-1.0, 1.0).acos()
    }
}

/// The smallest interior angle of triangle `abc`, radians (0 when degenerate).
pub fn min_angle(a: DVec3, b: DVec3, c: DVec3) -> f64 {
    angle_at(a, b, c).min(angle_at(b, c, a)).min(angle_at(c, a, b))
}

fn normal(a: DVec3, b: DVec3, c: DVec3) -> Option<DVec3> {
    (b - a).cross(c - a).try_normalize()
}

/// The two triangles that replace `t` and `s` when their shared edge is
/// flipped: `t` read from its corner `k` as `(a, b, c)`, `s` running the
/// edge the other way (`b → a`) with third corner `d`: `(a, d, c)` and
/// `(d, b, c)`, oriented as the pair was; also `d`. `None` where `s` does
/// not run `t`'s edge `a → b` backwards.
pub fn flipped_pair(t: [u32; 3], k: usize, s: [u32; 3]) -> Option<([[u32; 3]; 2], u32)> {
    let (a, b, c) = (t[k % 3], t[(k + 1) % 3], t[(k + 2) % 3]);
    let l = (0..3).find(|&l| s[l] == b && s[(l + 1) % 3] == a)?;
    let d = s[(l + 2) % 3];
    Some(([[a, d, c], [d, b, c]], d))
}

/// Flips the edges of `triangles` (corners into `positions`) by the
/// max–min angle criterion (module docs); an edge flips only between two
/// triangles of the same `region`. Returns the number of flips.
pub fn lawson_flips(positions: &[DVec3], triangles: &mut [[u32; 3]], region: &[usize], opts: &FlipOptions) -> usize {
    let n = positions.len() as u32;
    let cos_dihedral = opts.max_dihedral_deg.to_radians().cos();
    let gain = opts.min_gain_deg.to_radians();
    let ear_angle = opts.ear_angle_deg.to_radians();
    let cap_angle = opts.cap_angle_deg.to_radians();
    let pos = |v: u32| positions[v as usize];
    let mut flips = 0;
    for _ in 0..opts.max_passes {
        // edge (low, high) → the triangles using it and the corner it starts at
        let mut uses: BTreeMap<(u32, u32), Vec<(usize, usize)>> = BTreeMap::new();
        for (f, t) in triangles.iter().enumerate() {
            if t.iter().any(|&v| v >= n) {
                continue;
            }
            for k in 0..3 {
                let (a, b) = (t[k], t[(k + 1) % 3]);
                uses.entry((a.min(b), a.max(b))).or_default().push((f, k));
            }
        }
        let mut touched: BTreeSet<usize> = BTreeSet::new();
        // edges this pass made (`uses` is the pass's start)
        let mut made: BTreeSet<(u32, u32)> = BTreeSet::new();
        let mut pass_flips = 0;
        for u in uses.values() {
            let &[(f, k), (g, _)] = u.as_slice() else { continue };
            if region.get(f) != region.get(g) || touched.contains(&f) || touched.contains(&g) {
                continue;
            }
            let (t, s) = (triangles[f], triangles[g]);
            // t = (a, b, c) from corner k; s must run the edge the other way
            let (a, b, c) = (t[k], t[(k + 1) % 3], t[(k + 2) % 3]);
            let Some((new, d)) = flipped_pair(t, k, s) else { continue };
            let cd = (c.min(d), c.max(d));
            if c == d || uses.contains_key(&cd) || made.contains(&cd) {
                continue;
            }
            let (pa, pb, pc, pd) = (pos(a), pos(b), pos(c), pos(d));
            let (Some(n1), Some(n2)) = (normal(pa, pb, pc), normal(pb, pa, pd)) else { continue };
            // an edge of the triangle `face` shared with a triangle of another region
            let on_line = |p: u32, q: u32, face: usize| {
                uses.get(&(p.min(q), p.max(q))).is_some_and(|w| {
                    w.len() == 2 && w.iter().any(|&(h, _)| h != face && region.get(h) != region.get(face))
                })
            };
            let (at_c, at_d) = (angle_at(pc, pa, pb), angle_at(pd, pb, pa));
            let ear_c = (on_line(b, c, f) && on_line(c, a, f) && at_c >= ear_angle) || at_c >= cap_angle;
            let ear_d = (on_line(a, d, g) && on_line(d, b, g) && at_d >= ear_angle) || at_d >= cap_angle;
            let mean = match (ear_c, ear_d) {
                (true, false) => n2,
                (false, true) => n1,
                _ if n1.dot(n2) < cos_dihedral => continue,
                _ => n1 + n2,
            };
            let (Some(m1), Some(m2)) = (normal(pa, pd, pc), normal(pd, pb, pc)) else { continue };
            if m1.dot(mean) <= 0.0 || m2.dot(mean) <= 0.0 {
                continue;
            }
            let before = min_angle(pa, pb, pc).min(min_angle(pb, pa, pd));
            let after = min_angle(pa, pd, pc).min(min_angle(pd, pb, pc));
            if after <= before + gain {
                continue;
            }
            [triangles[f], triangles[g]] = new;
            touched.insert(f);
            touched.insert(g);
            made.insert(cd);
            pass_flips += 1;
        }
        flips += pass_flips;
        if pass_flips == 0 {
            break;
        }
    }
    flips
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A kite 2 long and 0.2 wide in the plane z = 0, its long diagonal 0–1,
    /// its short one 2–3.
    fn kite() -> [DVec3; 4] {
        [DVec3::new(-1.0, 0.0, 0.0), DVec3::new(1.0, 0.0, 0.0), DVec3::new(0.0, 0.1, 0.0), DVec3::new(0.0, -0.1, 0.0)]
    }

    /// How many triangles use each edge.
    fn edge_uses(t: &[[u32; 3]]) -> BTreeMap<(u32, u32), usize> {
        let mut uses = BTreeMap::new();
        for f in t {
            for k in 0..3 {
                let (a, b) = (f[k], f[(k + 1) % 3]);
                *uses.entry((a.min(b), a.max(b))).or_default() += 1;
            }
        }
        uses
    }

    /// A cap (its corners nearly on a line, lifted a little out of the
    /// surface: its normal 84° from its neighbour's) flips its long edge
    /// with `cap_angle_deg` 170 and stays with the default (none); the new
    /// triangles face the neighbour's way.
    #[test]
    fn a_cap_flips_whatever_its_normal_when_asked() {
        let p = [
            DVec3::new(-1.0, 0.0, 0.0),
            DVec3::new(1.0, 0.0, 0.0),
            DVec3::new(0.0, 0.001, 0.01),
            DVec3::new(0.0, -1.0, 0.0),
        ];
        assert!(angle_at(p[2], p[0], p[1]).to_degrees() > 178.0);
        let mut t = vec![[0, 1, 2], [1, 0, 3]];
        assert_eq!(lawson_flips(&p, &mut t, &[0, 0], &FlipOptions::default()), 0);
        let caps = FlipOptions { cap_angle_deg: 170.0, ..FlipOptions::default() };
        assert_eq!(lawson_flips(&p, &mut t, &[0, 0], &caps), 1);
        let uses = edge_uses(&t);
        assert!(uses.contains_key(&(2, 3)) && !uses.contains_key(&(0, 1)), "{uses:?}");
        for f in &t {
            let n = normal(p[f[0] as usize], p[f[1] as usize], p[f[2] as usize]).unwrap();
            assert!(n.z > 0.99, "{t:?}");
        }
    }

    /// A kite split along its long diagonal (two slivers) flips to the short one.
    #[test]
    fn a_sliver_pair_flips_to_the_short_diagonal() {
        let kite = kite();
        let mut t = vec![[0, 1, 2], [1, 0, 3]];
        assert_eq!(lawson_flips(&kite, &mut t, &[0, 0], &FlipOptions::default()), 1);
        let uses = edge_uses(&t);
        assert!(uses.contains_key(&(2, 3)) && !uses.contains_key(&(0, 1)), "{uses:?}");
        // orientation kept: both still face +z, as the input did
        for f in &t {
            let n = normal(kite[f[0] as usize], kite[f[1] as usize], kite[f[2] as usize]).unwrap();
            assert!(n.z > 0.99, "{t:?}");
        }
        // a rectangle's two diagonals are equally good: nothing flips
        let rect = [DVec3::ZERO, DVec3::new(1.0, 0.0, 0.0), DVec3::new(1.0, 0.2, 0.0), DVec3::new(0.0, 0.2, 0.0)];
        let mut r = vec![[0, 1, 2], [0, 2, 3]];
        assert_eq!(lawson_flips(&rect, &mut r, &[0, 0], &FlipOptions::default()), 0);
    }

    /// A triangle along a curved line between two regions (its corners
    /// three points of the line, lying across the surface: 90° to its
    /// neighbour) flips its chord into the surface; the same pair with the
    /// line's two edges on the mesh's boundary (no other region there)
    /// stays folded.
    #[test]
    fn an_ear_on_a_line_between_regions_flips_whatever_its_dihedral() {
        // the surface: the plane z = 0 above the line y = 0 (region 0), and below it (region 1);
        // the line runs -x → +x through c, bowed 0.2 out of the surface
        let p = [
            DVec3::new(-1.0, 0.0, 0.0),
            DVec3::new(1.0, 0.0, 0.0),
            DVec3::new(0.0, 0.0, 0.2),
            DVec3::new(0.0, 1.0, 0.0),
            DVec3::new(0.0, -1.0, 0.0),
        ];
        // region 0: the ear (0, 1, 2) and its neighbour (1, 0, 3); region 1: below the line
        let mut t = vec![[0, 1, 2], [1, 0, 3], [0, 2, 4], [2, 1, 4]];
        let regions = [0, 0, 1, 1];
        let before = normal(p[1], p[0], p[3]).unwrap();
        assert!(angle_at(p[2], p[0], p[1]).to_degrees() > 150.0);
        assert_eq!(lawson_flips(&p, &mut t, &regions, &FlipOptions::default()), 1);
        let uses = edge_uses(&t);
        assert!(uses.contains_key(&(2, 3)) && !uses.contains_key(&(0, 1)), "{t:?}");
        // the new triangles face as the neighbour did
        for f in &t[..2] {
            let n = normal(p[f[0] as usize], p[f[1] as usize], p[f[2] as usize]).unwrap();
            assert!(n.dot(before) > 0.0, "{t:?}");
        }
        // below 150° it stays; with no other region along its edges it stays
        let mut t = vec![[0, 1, 2], [1, 0, 3], [0, 2, 4], [2, 1, 4]];
        let strict = FlipOptions { ear_angle_deg: 170.0, ..FlipOptions::default() };
        assert_eq!(lawson_flips(&p, &mut t, &regions, &strict), 0);
        let mut alone = vec![[0, 1, 2], [1, 0, 3]];
        assert_eq!(lawson_flips(&p, &mut alone, &[0, 0], &FlipOptions::default()), 0);
    }

    /// Edges between regions, boundary edges and folded pairs stay.
    #[test]
    fn fixed_edges_stay() {
        let mut t = vec![[0, 1, 2], [1, 0, 3]];
        assert_eq!(lawson_flips(&kite(), &mut t, &[0, 1], &FlipOptions::default()), 0);
        // the same kite folded 90° about its long axis
        let mut folded = kite();
        folded[3] = DVec3::new(0.0, 0.0, -0.1);
        assert_eq!(lawson_flips(&folded, &mut t, &[0, 0], &FlipOptions::default()), 0);
        assert_eq!(t, vec![[0, 1, 2], [1, 0, 3]]);
    }

    /// Regression: two pairs that would flip to the same new edge `cd` in
    /// one pass (the authored bodysuit's coarse mesh got an edge of four
    /// triangles): only the first flips.
    #[test]
    fn two_flips_never_make_the_same_edge() {
        let mut p = kite().to_vec();
        p.extend([DVec3::new(-1.0, 0.0, 0.01), DVec3::new(1.0, 0.0, 0.01)]);
        let mut t = vec![[0, 1, 2], [1, 0, 3], [4, 5, 2], [5, 4, 3]];
        assert_eq!(lawson_flips(&p, &mut t, &[0; 4], &FlipOptions::default()), 1);
        let uses = edge_uses(&t);
        assert!(uses.values().all(|&n| n <= 2), "{uses:?}");
    }

    /// Planted answer: a fan of slivers in a planar convex polygon becomes
    /// Delaunay (no edge left whose opposite angles sum past π), triangle
    /// count and area kept.
    #[test]
    fn a_planar_fan_reaches_delaunay() {
        // points on an ellipse (no four cocircular), fanned from point 0
        let k = 12;
        let p: Vec<DVec3> = (0..k)
            .map(|i| {
                let a = std::f64::consts::TAU * i as f64 / k as f64 + 0.05 * (i % 3) as f64;
                DVec3::new(2.0 * a.cos(), a.sin(), 0.0)
            })
            .collect();
        let mut t: Vec<[u32; 3]> = (1..k as u32 - 1).map(|i| [0, i, i + 1]).collect();
        let area = |t: &[[u32; 3]]| -> f64 {
            t.iter()
                .map(|f| (p[f[1] as usize] - p[f[0] as usize]).cross(p[f[2] as usize] - p[f[0] as usize]).z / 2.0)
                .sum()
        };
        let (count, a0) = (t.len(), area(&t));
        let before =
            t.iter().map(|f| min_angle(p[f[0] as usize], p[f[1] as usize], p[f[2] as usize])).fold(f64::MAX, f64::min);
        let opts = FlipOptions { min_gain_deg: 0.0, ..FlipOptions::default() };
        assert!(lawson_flips(&p, &mut t, &vec![0; count], &opts) > 0);
        assert_eq!(t.len(), count);
        assert!((area(&t) - a0).abs() < 1e-12);
        let after =
            t.iter().map(|f| min_angle(p[f[0] as usize], p[f[1] as usize], p[f[2] as usize])).fold(f64::MAX, f64::min);
        assert!(after > before, "{after} vs {before}");
        // Delaunay: every interior edge's opposite angles sum to at most π
        let angle_at = |f: &[u32; 3], v: u32| {
            let i = f.iter().position(|&w| w == v).unwrap();
            let (o, q, r) = (p[f[i] as usize], p[f[(i + 1) % 3] as usize], p[f[(i + 2) % 3] as usize]);
            (q - o).angle_between(r - o)
        };
        for (i, f) in t.iter().enumerate() {
            for (j, g) in t.iter().enumerate().skip(i + 1) {
                let shared: Vec<u32> = f.iter().copied().filter(|v| g.contains(v)).collect();
                if shared.len() == 2 {
                    let c = *f.iter().find(|v| !shared.contains(v)).unwrap();
                    let d = *g.iter().find(|v| !shared.contains(v)).unwrap();
                    let s = angle_at(f, c) + angle_at(g, d);
                    assert!(s <= std::f64::consts::PI + 1e-9, "edge {shared:?} of {i},{j}: {s}");
                }
            }
        }
    }
}
