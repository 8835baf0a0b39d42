//! The topological graph `K^f` of a template by mesh simplification
//! (seed 000 §3.3, Fig. 8): a dense garment-like surface `M'` on the body
//! and a chosen set of encoded nodes → iterative Garland–Heckbert edge
//! contraction ([`crate::geom::simplify`]) in which an encoded node keeps
//! its position and two encoded nodes are never contracted together,
//! until every remaining edge joins two encoded nodes.
//!
//! Failure modes: those of [`simplify`] (non-manifold input, a free
//! vertex that cannot be removed without breaking the surface).

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
