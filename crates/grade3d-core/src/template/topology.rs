//! The topological graph `K^f` of a template by mesh simplification
//! (seed 000 §3.3, Fig. 8): a dense garment-like surface `M'` on the body
//! and a chosen set of encoded nodes → iterative Garland–Heckbert edge
//! contraction ([`crate::geom::simplify`]) in which an encoded node keeps
//! its position and two encoded nodes are never contracted together,
//! until every remaining edge joins two encoded nodes.
//!
//! Failure modes: those of [`simplify`] (non-manifold input, a free
//! vertex that cannot be removed without breaking the surface).

use glam::DVec3;

use crate::geom::mesh::{TriMesh, VertexId};
use crate::geom::simplify::{simplify, SimplifyError, SimplifyOptions};

/// The result of [`topology_by_simplification`].
#[derive(Debug, Clone)]
pub struct Topology {
    /// `M''`: the encoded nodes and the triangles between them.
    pub mesh: TriMesh,
    /// Where each encoded node ended up in `mesh`, in input order.
    pub nodes: Vec<VertexId>,
    /// Sum of the quadric errors of the contractions.
    pub total_quadric_error: f64,
    /// Largest quadric error of one contraction.
    pub max_quadric_error: f64,
}

/// Simplifies `dense` down to the edges between `encoded` vertices.
pub fn topology_by_simplification(
    dense: &TriMesh,
    encoded: &[VertexId],
    opts: &SimplifyOptions,
) -> Result<Topology, SimplifyError> {
    let opts = SimplifyOptions { target_faces: None, stop_when_only_locked_edges: true, ..opts.clone() };
    let s = simplify(dense, encoded, &opts)?;
    Ok(Topology {
        mesh: s.mesh,
        nodes: s.locked_output,
        total_quadric_error: s.total_error,
        max_quadric_error: s.max_error,
    })
}

/// Fraction of the mesh height within which a ring's vertices are sought
/// around each ring level.
const RING_BAND: f64 = 0.15;

/// Encoded nodes for a tube-like dense garment (a skirt, a sleeve): `rings`
/// evenly spaced heights from the top to the bottom of `dense`, and at each
/// `per_ring` vertices nearest to evenly spaced directions about the
/// vertical axis through the bounding-box centre (front first, then
/// towards the body's left). Duplicates are dropped; order is ring by ring.
/// An automatic stand-in for the interactive choice of seed 000 Fig. 8(c).
pub fn encoded_rings(dense: &TriMesh, rings: usize, per_ring: usize) -> Vec<VertexId> {
    let bb = dense.aabb();
    let centre = bb.centre();
    let height = bb.size().y;
    let mut encoded: Vec<VertexId> = Vec::new();
    for r in 0..rings {
        let level = if rings > 1 { bb.max.y - height * r as f64 / (rings - 1) as f64 } else { centre.y };
        for k in 0..per_ring {
            let ang = std::f64::consts::TAU * k as f64 / per_ring as f64;
            let dir = DVec3::new(ang.sin(), 0.0, ang.cos());
            let score = |v: usize| {
                let p = dense.positions()[v];
                (p - centre).with_y(0.0).normalize_or_zero().distance(dir) + (p.y - level).abs()
            };
            let best = (0..dense.vertex_count())
                .filter(|&v| (dense.positions()[v].y - level).abs() < RING_BAND * height)
                .min_by(|&a, &b| score(a).total_cmp(&score(b)));
            if let Some(v) = best.map(|v| VertexId(v as u32)) {
                if !encoded.contains(&v) {
                    encoded.push(v);
                }
            }
        }
    }
    encoded
}
