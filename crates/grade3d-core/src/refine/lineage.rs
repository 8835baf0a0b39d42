//! The lineage of a refinement (issue #16, item 2): which vertex each
//! level's 1-to-4 split put on each edge, recorded by the split itself
//! ([`crate::refine::subdivide::refine`] returns it in [`Refined`]) so that
//! the pattern stage reads the refined numbering instead of replaying it.
//!
//! Contract: the split of [`crate::refine::subdivide`] keeps old vertex
//! ids, gives the new vertex of the `k`-th edge of `M_j` (in
//! [`crate::refine::subdivide::edge_keys`] order) the id `n_j + k`, and
//! makes face `f` of `M_j` faces `4f … 4f+3` of `M_{j+1}`. Hence the fine
//! chain along a coarse edge `(a, b)` is `chain(a, b) = chain(a, m) ⧺
//! chain(m, b)`, `m` the split vertex of `(a, b)` ([`Lineage::chain`]).
//!
//! [`Refined`]: crate::refine::subdivide::Refined

use std::collections::BTreeMap;

use crate::geom::mesh::VertexId;
use crate::geom::topology::MeshEdge;

/// The fine vertex of coarse node `node`: the split keeps old ids, so
/// template node `i` is fine vertex `i` at every level (module docs).
pub fn node_vertex(node: u32) -> VertexId {
    VertexId(node)
}

/// The template node a fine vertex is, if it is one (`nodes` the template's
/// node count): the inverse of [`node_vertex`].
pub fn vertex_node(v: VertexId, nodes: usize) -> Option<u32> {
    (v.idx() < nodes).then_some(v.0)
}

/// The split vertex of every edge, level by level.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct Lineage {
    /// Per level `j = 0 … L−1`: the split vertex of each edge of `M_j`.
    midpoints: Vec<BTreeMap<MeshEdge, VertexId>>,
}

impl Lineage {
    /// No level: the coarse mesh itself.
    pub fn new() -> Self {
        Self::default()
    }

    /// Records one more level: `midpoints[(a, b)]` is the vertex the split
    /// put on edge `(a, b)`.
    pub fn push_level(&mut self, midpoints: BTreeMap<MeshEdge, VertexId>) {
        self.midpoints.push(midpoints);
    }

    /// Levels recorded.
    pub fn levels(&self) -> usize {
        self.midpoints.len()
    }

    /// The fine vertices along the coarse edge `a → b`, `a` first and `b` last
    /// (`2^L + 1` of them); `None` if `(a, b)` is not an edge of the coarse mesh.
    pub fn chain(&self, a: VertexId, b: VertexId) -> Option<Vec<VertexId>> {
        let mut chain = vec![a, b];
        for mids in &self.midpoints {
            let mut next = Vec::with_capacity(2 * chain.len() - 1);
            for w in chain.windows(2) {
                next.push(w[0]);
                next.push(*mids.get(&MeshEdge::new(w[0], w[1]))?);
            }
            next.push(*chain.last()?);
            chain = next;
        }
        Some(chain)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn chains_double_per_level_and_unknown_edges_have_none() {
        // one triangle 0-1-2 split twice: level 0 puts 3, 4, 5 on (0,1), (0,2), (1,2)
        let v = VertexId;
        let level =
            |splits: &[(u32, u32, u32)]| splits.iter().map(|&(a, b, m)| (MeshEdge::new(v(a), v(b)), v(m))).collect();
        let mut l = Lineage::new();
        assert_eq!(l.chain(v(0), v(1)), Some(vec![v(0), v(1)]));
        l.push_level(level(&[(0, 1, 3), (0, 2, 4), (1, 2, 5)]));
        l.push_level(level(&[(0, 3, 6), (1, 3, 7)]));
        assert_eq!(l.levels(), 2);
        assert_eq!(l.chain(v(1), v(0)), Some([1, 7, 3, 6, 0].map(v).to_vec()));
        assert_eq!(l.chain(v(0), v(2)), None, "level 1 has no split of (0, 4)");
        assert_eq!(l.chain(v(0), v(9)), None);
    }
}
