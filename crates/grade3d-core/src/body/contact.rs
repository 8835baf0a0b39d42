//! Thigh contact: where a body's legs press into each other below the
//! crotch, so that no pair of trouser legs can pass between them outside the
//! body (issue #13, items 1 and 3).
//!
//! **Method.** On a body whose legs stand apart, the mid-sagittal plane
//! meets the body below the crotch point nowhere, or only where the crotch
//! itself curves down a little, and there the surface is mirror-symmetric
//! about the plane: its normal lies in the plane. Where heavy thighs press
//! together, the plane cuts through both inner thighs below the crotch, and
//! there the surface faces across it. The body is cut by the mid-sagittal
//! plane `Π` (through the mean midpoint of the left/right landmark pairs,
//! normal `N` the mean right-to-left direction made horizontal: the plane of
//! the midline check) and by `Π` moved ±`g/2` along `N` (`g`
//! [`ContactOptions::cloth_gap_mm`]: thighs nearer than a cloth's thickness
//! are in contact too); the section points `x` with
//!
//! ```text
//! (x − p_crotch)·up < 0,   |n(x)·N| ≥ c_n      (up +Y, n the surface normal, c_n ContactOptions::min_normal_across)
//! ```
//!
//! are points of contact, and the thighs are in contact when they reach at
//! least `d_c` ([`ContactOptions::min_depth_mm`]) below the crotch point.
//! The contact is reported by how far it reaches below the crotch and how
//! long it runs front to back.
//!
//! **Why it matters (a proof, not a tolerance).** Take a horizontal plane at
//! a height `h` below the garment's crotch, where the body's section is the
//! left thigh's region `L` and the right thigh's `R`, and contact means
//! `L ∪ R` is connected. A trouser leg at `h` is a closed curve `C_L` that
//! winds once around `L` and not around `R`. If `C_L` met no body
//! triangle it would lie outside the connected set `L ∪ R`, so its winding
//! number would be the same at every point of `L ∪ R`: it would wind around
//! `R` too. So at every height where the thighs touch, each trouser leg
//! crosses the body's surface: issue #13's bar of zero intersecting
//! garment/body triangle pairs cannot hold there for any two-legged
//! garment, at any resolution. The report counts the pairs left within
//! [`ContactOptions::reach_mm`] of the contact separately, and names the
//! contact as a warning.
//!
//! **Preconditions**: a feature body's mesh (Y up) and its crotch point.
//! **Failure modes**: none; without a left/right landmark pair or a crotch
//! point, no contact is looked for.

use glam::DVec3;
use serde::{Deserialize, Serialize};

use crate::geom::mesh::TriMesh;
use crate::geom::plane::Plane;
use crate::geom::slice::slice;

/// Millimetres per metre.
const MM_PER_M: f64 = 1e3;

/// Knobs of the thigh contact test.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct ContactOptions {
    /// Thighs nearer each other than this are in contact, mm. Default 1
    /// (the fixed vertices' clearance, a cloth's thickness: no cloth fits).
    pub cloth_gap_mm: f64,
    /// The points of contact must reach at least this far below the crotch
    /// point, mm. Default 10. Over issue #13's population (40 bodies, each
    /// as the hm08 mesh and as a scan-like copy with 1 mm noise), the 78
    /// whose thighs stand apart reach at most 4.1 mm (the scans of heavy
    /// thighs that nearly touch); the one body whose thighs press together
    /// 16.6 mm (hm08 mesh) and 17.3 mm (scan), over 122 mm front to back.
    pub min_depth_mm: f64,
    /// Section points where the surface normal makes at least this cosine
    /// with the mid-sagittal normal are on a thigh's inner side; others on
    /// the crotch itself, count (a cosine). Default 0.5 (60°).
    pub min_normal_across: f64,
    /// Intersecting garment/body pairs whose body or garment triangle has a
    /// corner within this of the contact are counted as at the contact, mm.
    /// Default 30 (about one garment edge: the triangles that cross between
    /// the thighs and their neighbours in the groove running up into the
    /// crotch). On the population's one body with pressed thighs, all 114
    /// (hm08 mesh) and 62 (scan) pairs the trousers leave are within it.
    pub reach_mm: f64,
}

impl Default for ContactOptions {
    fn default() -> Self {
        Self { cloth_gap_mm: 1.0, min_depth_mm: 10.0, min_normal_across: 0.5, reach_mm: 30.0 }
    }
}

/// Where the thighs press into each other (module docs).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ThighContact {
    /// The section points of contact, m.
    #[serde(skip)]
    pub points: Vec<DVec3>,
    /// How far the contact reaches below the crotch point, mm.
    pub depth_below_crotch_mm: f64,
    /// Its extent front to back (within the mid-sagittal plane), mm.
    pub length_mm: f64,
    /// [`ContactOptions::reach_mm`] it was found with, mm.
    pub reach_mm: f64,
}

impl ThighContact {
    /// Distance from `p` to the nearest point of contact, m.
    pub fn distance(&self, p: DVec3) -> f64 {
        self.points.iter().map(|q| q.distance(p)).fold(f64::INFINITY, f64::min)
    }

    /// Whether the triangle with corners `t` has a corner within
    /// [`Self::reach_mm`] of the contact (a crossing there is unavoidable).
    pub fn reaches(&self, t: &[DVec3; 3]) -> bool {
        t.iter().any(|&p| self.distance(p) * MM_PER_M <= self.reach_mm)
    }

    /// The contact moved by the rigid motion `x ↦ R x + t`.
    pub fn transformed(&self, map: impl Fn(DVec3) -> DVec3) -> Self {
        Self { points: self.points.iter().map(|&p| map(p)).collect(), ..*self }
    }
}

/// The thigh contact of `mesh` (module docs), `midsagittal` the body's
/// mid-sagittal plane, `crotch` its crotch point; `None` where the legs
/// stand apart.
pub fn thigh_contact(
    mesh: &TriMesh,
    midsagittal: &Plane,
    crotch: DVec3,
    opts: &ContactOptions,
) -> Option<ThighContact> {
    let up = DVec3::Y;
    let half = 0.5 * opts.cloth_gap_mm / MM_PER_M;
    let min_depth = opts.min_depth_mm / MM_PER_M;
    let normals = mesh.vertex_normals();
    let pos = mesh.positions();
    let mut points = Vec::new();
    for shift in [-half, 0.0, half] {
        let plane = Plane { normal: midsagittal.normal, offset: midsagittal.offset + shift };
        for s in slice(mesh, &plane) {
            for (&x, &(a, b)) in s.polyline.points.iter().zip(&s.edges) {
                if (x - crotch).dot(up) >= 0.0 {
                    continue;
                }
                // the surface normal where the section crosses edge (a, b), interpolated
                let (pa, pb) = (pos[a.idx()], pos[b.idx()]);
                let t = if pa == pb { 0.5 } else { ((x - pa).dot(pb - pa) / pa.distance_squared(pb)).clamp(0.0, 1.0) };
                let n = normals[a.idx()].lerp(normals[b.idx()], t).normalize_or_zero();
                if n.dot(midsagittal.normal).abs() >= opts.min_normal_across {
                    points.push(x);
                }
            }
        }
    }
    let depth = points.iter().map(|&x| -(x - crotch).dot(up)).fold(0.0, f64::max);
    if points.is_empty() || depth < min_depth {
        return None;
    }
    let along = midsagittal.normal.cross(up).normalize_or_zero();
    let (lo, hi) =
        points.iter().map(|&x| x.dot(along)).fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), t| (a.min(t), b.max(t)));
    Some(ThighContact {
        points,
        depth_below_crotch_mm: depth * MM_PER_M,
        length_mm: (hi - lo) * MM_PER_M,
        reach_mm: opts.reach_mm,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Two vertical boxes ("legs", 0.1 m wide in x, 0.12 m deep in z, cut
    /// into 0.05 m slabs so that vertex normals are those of their faces up
    /// the sides) under a torso box whose bottom (the crotch) is at y = 0,
    /// `gap` apart across x = 0.
    fn legs(gap: f64) -> TriMesh {
        let mut pos = Vec::new();
        let mut tris = Vec::new();
        let mut bx = |lo: DVec3, hi: DVec3, slabs: u32| {
            let b = pos.len() as u32;
            // ring k: corners (lo.x, lo.z), (hi.x, lo.z), (hi.x, hi.z), (lo.x, hi.z) at height y_k
            for k in 0..=slabs {
                let y = lo.y + (hi.y - lo.y) * f64::from(k) / f64::from(slabs);
                for (x, z) in [(lo.x, lo.z), (hi.x, lo.z), (hi.x, hi.z), (lo.x, hi.z)] {
                    pos.push(DVec3::new(x, y, z));
                }
            }
            let v = |k: u32, c: u32| crate::geom::mesh::VertexId(b + 4 * k + c % 4);
            for k in 0..slabs {
                for c in 0..4 {
                    tris.push([v(k, c), v(k + 1, c + 1), v(k, c + 1)]);
                    tris.push([v(k, c), v(k + 1, c), v(k + 1, c + 1)]);
                }
            }
            tris.push([v(0, 0), v(0, 1), v(0, 2)]);
            tris.push([v(0, 0), v(0, 2), v(0, 3)]);
            tris.push([v(slabs, 0), v(slabs, 2), v(slabs, 1)]);
            tris.push([v(slabs, 0), v(slabs, 3), v(slabs, 2)]);
        };
        let h = gap / 2.0;
        bx(DVec3::new(h, -0.7, -0.06), DVec3::new(h + 0.1, 0.0, 0.06), 14);
        bx(DVec3::new(-h - 0.1, -0.7, -0.06), DVec3::new(-h, 0.0, 0.06), 14);
        bx(DVec3::new(-0.2, 0.0, -0.1), DVec3::new(0.2, 0.5, 0.1), 10);
        TriMesh::new(pos, tris).unwrap()
    }

    fn plane() -> Plane {
        Plane::from_point_normal(DVec3::ZERO, DVec3::X).unwrap()
    }

    #[test]
    fn legs_apart_have_no_contact() {
        assert_eq!(thigh_contact(&legs(0.05), &plane(), DVec3::ZERO, &ContactOptions::default()), None);
        // 1.2 mm apart: more than a cloth's thickness
        assert_eq!(thigh_contact(&legs(0.0012), &plane(), DVec3::ZERO, &ContactOptions::default()), None);
    }

    #[test]
    fn the_crotch_itself_is_not_contact() {
        // the crotch point 20 mm above the torso's bottom: the plane meets the
        // body 20 mm below it, but where the surface faces down, not across
        let crotch = DVec3::new(0.0, 0.02, 0.0);
        assert_eq!(thigh_contact(&legs(0.05), &plane(), crotch, &ContactOptions::default()), None);
        // facing across is what counts: with no normal test the bottom is taken for contact
        let any = ContactOptions { min_normal_across: 0.0, ..Default::default() };
        let c = thigh_contact(&legs(0.05), &plane(), crotch, &any).unwrap();
        assert!((c.depth_below_crotch_mm - 20.0).abs() < 1e-6, "{}", c.depth_below_crotch_mm);
    }

    #[test]
    fn legs_pressed_together_are_in_contact_down_their_whole_length() {
        // overlapping by 4 mm, and touching within a cloth's thickness (0.8 mm apart)
        for gap in [-0.004, 0.0008] {
            let c = thigh_contact(&legs(gap), &plane(), DVec3::ZERO, &ContactOptions::default())
                .unwrap_or_else(|| panic!("gap {gap}"));
            assert!((c.depth_below_crotch_mm - 700.0).abs() < 1e-6, "{}", c.depth_below_crotch_mm);
            assert!((c.length_mm - 120.0).abs() < 1e-6, "{}", c.length_mm);
            // up the inner sides, front and back (within the ±0.5 mm planes)
            assert!(c.distance(DVec3::new(0.0, -0.3, 0.06)) < 0.6e-3);
            assert!((c.distance(DVec3::new(0.0, -0.3, 0.09)) - 0.03).abs() < 1e-5);
            let t = [DVec3::new(0.0, -0.2, 0.08), DVec3::new(0.0, -0.2, 0.1), DVec3::new(0.01, -0.25, 0.1)];
            assert!(c.reaches(&t), "20 mm from the contact");
            assert!(!c.reaches(&t.map(|p| p + DVec3::new(0.0, 0.0, 0.02))), "40 mm from it");
        }
    }
}
