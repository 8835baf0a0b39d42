//! Cutting the refined garment `M_L` into its panels along the template's
//! seams (seed 000 §6: "the 3D garment is cut into pieces along the seam
//! lines, and each piece is flattened").
//!
//! # Contract
//!
//! **Lineage.** The 1-to-4 split of [`crate::refine::subdivide`] numbers
//! everything deterministically: face `f` of level `j` becomes faces
//! `4f … 4f+3` of level `j+1`, and the new vertex of the `k`-th edge of
//! [`edge_keys`] gets id `n_j + k`; old vertices keep their ids. Hence
//! * the fine face `f` of `M_L` lies in the coarse face `f / 4^L`, so a
//!   panel is the set of fine faces whose coarse face is one of the panel's
//!   template faces;
//! * coarse node `i` is fine vertex `i`;
//! * the fine chain along the coarse edge `(a, b)` is
//!   `chain(a, b) = chain(a, m) ⧺ chain(m, b)` with `m` the split vertex of
//!   `(a, b)`, as the refinement recorded it ([`Lineage`]; issue #16: no
//!   longer replayed here from the coarse triangles).
//!
//! **Panels.** Each [`Panel`] is the sub-mesh of its fine faces with its own
//! vertex numbering (`global[local]`), so vertices on a seam are duplicated
//! into both panels — the cut. Its outline is its one boundary loop, run in
//! the faces' orientation (counter-clockwise seen from outside). Seams are
//! the fine chains of the template seam's coarse edges, in order.
//!
//! **Preconditions.** The fine mesh and its lineage are what
//! [`crate::refine::subdivide::refine`] made of the template's coarse mesh
//! (face count `4^L ×` the template's, `L` the lineage's levels). **Failure modes**: [`PanelError`] naming the
//! panel, seam or edge — face count mismatch, a panel that is not a disc
//! (not exactly one boundary loop), a seam edge not on both panels'
//! outlines, a seam whose edges do not chain.

use std::collections::HashMap;

use glam::DVec3;
use typed_index_collections::{TiSlice, TiVec};

use crate::geom::mesh::{boundary_loops, typed_id, FaceId, VertexId};
use crate::geom::topology::MeshEdge;
use crate::refine::lineage::Lineage;
use crate::template::format::Template;

typed_id!(
    /// A vertex of one panel, in the panel's own numbering
    /// ([`Panel::global`] maps it to the garment mesh's [`VertexId`]).
    ///
    /// The two numberings do not mix: the garment's data is reached through
    /// the panel's map,
    ///
    /// ```
    /// # use grade3d_core::{pattern::panels::{Panel, PanelVertex}, refine::subdivide::RefineMesh};
    /// fn garment_point(mesh: &RefineMesh, panel: &Panel, v: PanelVertex) -> glam::DVec3 {
    ///     mesh.positions[panel.global[v]]
    /// }
    /// ```
    ///
    /// and a panel's vertex does not index it:
    ///
    /// ```compile_fail
    /// # use grade3d_core::{pattern::panels::{Panel, PanelVertex}, refine::subdivide::RefineMesh};
    /// fn garment_point(mesh: &RefineMesh, panel: &Panel, v: PanelVertex) -> glam::DVec3 {
    ///     mesh.positions[v]
    /// }
    /// ```
    PanelVertex
);

typed_id!(
    /// A triangle of one panel ([`Panel::triangles`]).
    PanelFace
);

/// Why a panel could not be cut out.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum PanelError {
    /// The fine mesh does not have `4^levels ×` the template's faces.
    #[error("fine mesh has {fine} faces; {levels} levels of a {coarse}-face template give {expected}")]
    FaceCount {
        /// Fine faces.
        fine: usize,
        /// Template faces.
        coarse: usize,
        /// Levels.
        levels: usize,
        /// `4^levels × coarse`.
        expected: usize,
    },
    /// A panel's faces do not form a disc.
    #[error("panel '{panel}' has {loops} boundary loops; a pattern piece must be a disc (one loop)")]
    NotADisc {
        /// Panel name.
        panel: String,
        /// Boundary loops found.
        loops: usize,
    },
    /// A seam's coarse edge is not on a panel's outline.
    #[error("seam '{seam}': template edge {edge} is not on the outline of panel '{panel}'")]
    SeamOffOutline {
        /// Seam name.
        seam: String,
        /// Template edge.
        edge: u32,
        /// Panel name.
        panel: String,
    },
    /// Consecutive seam edges share no node.
    #[error("seam '{seam}': template edges {first} and {second} do not meet")]
    SeamNotChained {
        /// Seam name.
        seam: String,
        /// An edge.
        first: u32,
        /// The next edge.
        second: u32,
    },
    /// A dart's chain does not run from the panel's outline into its interior.
    #[error("dart '{dart}': {reason}")]
    BadDart {
        /// Dart name.
        dart: String,
        /// What is wrong.
        reason: String,
    },
    /// A seam names a panel that does not exist.
    #[error("seam '{seam}' names unknown panel '{panel}'")]
    UnknownPanel {
        /// Seam name.
        seam: String,
        /// Panel name.
        panel: String,
    },
}

/// One panel cut out of the fine mesh.
#[derive(Debug, Clone, PartialEq)]
pub struct Panel {
    /// Template panel name.
    pub name: String,
    /// Index of the panel in the template.
    pub index: usize,
    /// Fine vertex of each local vertex: ascending for the first
    /// [`Panel::unique`] vertices, then the dart duplicates.
    pub global: TiVec<PanelVertex, VertexId>,
    /// How many local vertices precede the dart duplicates.
    pub unique: usize,
    /// The panel's darts, slit open.
    pub darts: Vec<DartLegs>,
    /// Local positions (copied from the fine mesh).
    pub positions: TiVec<PanelVertex, DVec3>,
    /// Triangles in local ids, orientation kept.
    pub triangles: TiVec<PanelFace, [PanelVertex; 3]>,
    /// The boundary loop in local ids, in the faces' orientation, starting at
    /// its smallest template node.
    pub outline: Vec<PanelVertex>,
}

impl Panel {
    /// Local id of a fine vertex, if the panel has it (on a dart, the vertex of
    /// the first leg).
    pub fn local(&self, global: VertexId) -> Option<PanelVertex> {
        self.global.raw[..self.unique].binary_search(&global).ok().map(PanelVertex::from)
    }
}

impl Panel {
    /// Slits the panel open along `chain` (local ids, from a vertex on the
    /// outline to an interior apex) and records it as the dart `name`: the
    /// vertices of the chain but the apex are duplicated, the faces on the
    /// left of the chain take the duplicates, and the outline is found again
    /// (it now runs down one leg and up the other). Used for darts found
    /// where the flattening strains most ([`super::darts`]).
    ///
    /// # Errors
    /// Why the chain cannot be slit (its first edge is not in the panel, it
    /// does not start on the outline, or the panel would stop being a disc);
    /// the panel is left unchanged then.
    pub fn add_dart(&mut self, name: &str, chain: &[PanelVertex]) -> Result<(), String> {
        let mut triangles = self.triangles.clone();
        let mut global = self.global.clone();
        let legs = slit(&mut triangles, &mut global, chain)?;
        let outline = disc_outline(&triangles, &global)
            .map_err(|loops| format!("the slit leaves {loops} boundary loops, not one"))?;
        for &v in &chain[..chain.len() - 1] {
            self.positions.push(self.positions[v]);
        }
        self.triangles = triangles;
        self.global = global;
        self.outline = outline;
        self.darts.push(DartLegs { name: name.to_string(), a: chain.to_vec(), b: legs });
        Ok(())
    }

    /// A seam's fine chain (global ids) as directed edges of this panel's
    /// outline, in local ids, one per consecutive pair; `None` if a pair is
    /// not an outline edge. Where a dart opens on the seam, the edges either
    /// side of its mouth end on the two copies of the mouth vertex.
    pub fn seam_edges(&self, chain: &[VertexId]) -> Option<Vec<[PanelVertex; 2]>> {
        let n = self.outline.len();
        let mut by_pair: HashMap<(VertexId, VertexId), [PanelVertex; 2]> = HashMap::with_capacity(2 * n);
        for k in 0..n {
            let (u, w) = (self.outline[k], self.outline[(k + 1) % n]);
            let (gu, gw) = (self.global[u], self.global[w]);
            by_pair.entry((gu, gw)).or_insert([u, w]);
            by_pair.entry((gw, gu)).or_insert([w, u]);
        }
        chain.windows(2).map(|p| by_pair.get(&(p[0], p[1])).copied()).collect()
    }

    /// A seam's fine chain as runs of local ids along the outline: one run,
    /// or one more for each dart opening on the seam (module docs of
    /// [`super::darts`]); `None` if the seam is not on this panel's outline.
    pub fn seam_runs(&self, chain: &[VertexId]) -> Option<Vec<Vec<PanelVertex>>> {
        let edges = self.seam_edges(chain)?;
        let mut runs: Vec<Vec<PanelVertex>> = Vec::new();
        for [u, w] in edges {
            match runs.last_mut() {
                Some(run) if run.last() == Some(&u) => run.push(w),
                _ => runs.push(vec![u, w]),
            }
        }
        Some(runs)
    }

    /// The outline with every dart closed: the legs' vertices (all but the two
    /// openings) left out, so the line runs straight across each dart's opening.
    /// This is the sew line; the legs are drawn as internal lines.
    pub fn rim(&self) -> Vec<PanelVertex> {
        let legs: std::collections::HashSet<PanelVertex> =
            self.darts.iter().flat_map(|d| d.a[1..].iter().chain(&d.b[1..]).copied()).collect();
        self.outline.iter().copied().filter(|v| !legs.contains(v)).collect()
    }
}

/// A dart slit open in a panel: its two legs in local ids, each from the
/// opening on the outline to the shared apex.
#[derive(Debug, Clone, PartialEq)]
pub struct DartLegs {
    /// Dart name.
    pub name: String,
    /// First leg (the original vertices).
    pub a: Vec<PanelVertex>,
    /// Second leg (the duplicates, then the apex).
    pub b: Vec<PanelVertex>,
}

/// A seam: the fine chain along its coarse edges, and the two panels.
#[derive(Debug, Clone, PartialEq)]
pub struct SeamChain {
    /// Seam name.
    pub name: String,
    /// Panel index of side a.
    pub panel_a: usize,
    /// Panel index of side b.
    pub panel_b: usize,
    /// Fine vertices along the seam.
    pub chain: Vec<VertexId>,
}

/// Cuts the fine mesh (`positions`, `triangles`) the refinement made of the
/// template `t`, with its `lineage`, into its panels, the template's darts
/// slit open, and seams (module docs): [`cut_plain`] then [`CutGarment::darted`].
///
/// # Errors
/// [`PanelError`] (module docs).
pub fn cut(
    t: &Template,
    positions: &TiSlice<VertexId, DVec3>,
    triangles: &TiSlice<FaceId, [VertexId; 3]>,
    lineage: &Lineage,
) -> Result<(Vec<Panel>, Vec<SeamChain>), PanelError> {
    let plain = cut_plain(t, positions, triangles, lineage)?;
    Ok((plain.darted(t, positions, lineage)?, plain.seams))
}

/// The garment cut along its seams, no dart slit yet: the first step of
/// the pattern stage, made once per grade (issue #16, item 3); each pass
/// that tries a set of declared darts slits them into copies of these
/// panels ([`CutGarment::darted`]) instead of cutting the mesh again.
#[derive(Debug, Clone, PartialEq)]
pub struct CutGarment {
    /// The panels, in template order, without darts.
    pub panels: Vec<Panel>,
    /// The seams, in template order.
    pub seams: Vec<SeamChain>,
}

impl CutGarment {
    /// The panels with the darts `t` declares slit open, in `t`'s order (a
    /// chain from the outline to the apex; `positions` the fine mesh's).
    ///
    /// # Errors
    /// [`PanelError::BadDart`] for a dart whose edges do not meet end to end,
    /// that is not inside its panel or cannot be slit;
    /// [`PanelError::NotADisc`] if a slit panel is not a disc.
    pub fn darted(
        &self,
        t: &Template,
        positions: &TiSlice<VertexId, DVec3>,
        lineage: &Lineage,
    ) -> Result<Vec<Panel>, PanelError> {
        let mut out = Vec::with_capacity(self.panels.len());
        for plain in &self.panels {
            let mut local_tris = plain.triangles.clone();
            let mut global = plain.global.clone();
            let mut darts = Vec::new();
            for d in t.darts.iter().filter(|d| d.panel == plain.name) {
                let chain = seam_chain(t, lineage, &d.name, &d.edges).map_err(|_| PanelError::BadDart {
                    dart: d.name.clone(),
                    reason: "its edges do not meet end to end".into(),
                })?;
                let Some(mut chain) = chain
                    .iter()
                    .map(|&g| global.raw.binary_search(&g).ok().map(PanelVertex::from))
                    .collect::<Option<Vec<PanelVertex>>>()
                else {
                    return Err(PanelError::BadDart {
                        dart: d.name.clone(),
                        reason: format!("not inside panel '{}'", plain.name),
                    });
                };
                // run it from the outline to the apex
                let rim: std::collections::HashSet<PanelVertex> =
                    boundary_loops(&local_tris.raw).into_iter().flatten().collect();
                if !rim.contains(&chain[0]) && chain.last().is_some_and(|v| rim.contains(v)) {
                    chain.reverse();
                }
                let legs = slit(&mut local_tris, &mut global, &chain)
                    .map_err(|reason| PanelError::BadDart { dart: d.name.clone(), reason })?;
                darts.push(DartLegs { name: d.name.clone(), a: chain, b: legs });
            }
            if darts.is_empty() {
                out.push(plain.clone());
                continue;
            }
            let outline = disc_outline(&local_tris, &global)
                .map_err(|loops| PanelError::NotADisc { panel: plain.name.clone(), loops })?;
            out.push(Panel {
                name: plain.name.clone(),
                index: plain.index,
                positions: global.iter().map(|&g| positions[g]).collect(),
                global,
                unique: plain.unique,
                darts,
                triangles: local_tris,
                outline,
            });
        }
        Ok(out)
    }
}

/// Cuts the fine mesh into its panels (no dart slit) and seams: the
/// [`CutGarment`] step.
///
/// # Errors
/// [`PanelError`] (module docs).
pub fn cut_plain(
    t: &Template,
    positions: &TiSlice<VertexId, DVec3>,
    triangles: &TiSlice<FaceId, [VertexId; 3]>,
    lineage: &Lineage,
) -> Result<CutGarment, PanelError> {
    let levels = lineage.levels();
    let coarse_faces = t.faces.len();
    let per = 1usize << (2 * levels);
    let expected = coarse_faces * per;
    if triangles.len() != expected {
        return Err(PanelError::FaceCount { fine: triangles.len(), coarse: coarse_faces, levels, expected });
    }
    let mut panels = Vec::with_capacity(t.panels.len());
    for (index, p) in t.panels.iter().enumerate() {
        // face f of the coarse mesh is faces f·4^L … (f+1)·4^L − 1 of the fine one (lineage)
        let fine: Vec<[VertexId; 3]> = p
            .faces
            .iter()
            .flat_map(|&f| triangles.raw[f as usize * per..(f as usize + 1) * per].iter().copied())
            .collect();
        let mut global: Vec<VertexId> = fine.iter().flatten().copied().collect();
        global.sort_unstable();
        global.dedup();
        let global: TiVec<PanelVertex, VertexId> = global.into();
        let local = |g: VertexId| global.raw.binary_search(&g).map(PanelVertex::from).unwrap_or(PanelVertex(u32::MAX));
        let local_tris: TiVec<PanelFace, [PanelVertex; 3]> = fine.iter().map(|t| t.map(local)).collect();
        let unique = global.len();
        let darts = Vec::new();
        let outline = disc_outline(&local_tris, &global)
            .map_err(|loops| PanelError::NotADisc { panel: p.name.clone(), loops })?;
        let positions = global.iter().map(|&g| positions[g]).collect();
        panels.push(Panel {
            name: p.name.clone(),
            index,
            global,
            unique,
            darts,
            positions,
            triangles: local_tris,
            outline,
        });
    }
    let mut seams = Vec::with_capacity(t.seams.len());
    for s in &t.seams {
        let find = |name: &str| {
            t.panels
                .iter()
                .position(|p| p.name == name)
                .ok_or_else(|| PanelError::UnknownPanel { seam: s.name.clone(), panel: name.to_string() })
        };
        let (a, b) = (find(&s.panel_a)?, find(&s.panel_b)?);
        let chain = seam_chain(t, lineage, s.name.as_str(), &s.edges)?;
        for &pi in &[a, b] {
            let panel = &panels[pi];
            let on_outline: std::collections::HashSet<VertexId> =
                panel.outline.iter().map(|&l| panel.global[l]).collect();
            if let Some(&off) = chain.iter().find(|g| !on_outline.contains(g)) {
                let edge = s
                    .edges
                    .iter()
                    .copied()
                    .find(|&e| {
                        let e = &t.edges[e as usize];
                        lineage.chain(VertexId(e.start), VertexId(e.end)).is_some_and(|c| c.contains(&off))
                    })
                    .unwrap_or(0);
                return Err(PanelError::SeamOffOutline { seam: s.name.clone(), edge, panel: panel.name.clone() });
            }
        }
        seams.push(SeamChain { name: s.name.clone(), panel_a: a, panel_b: b, chain });
    }
    Ok(CutGarment { panels, seams })
}

/// Slits the triangles along `chain` (local ids, from a boundary vertex to an
/// interior apex): the faces on the left of the chain — those reached from the
/// face holding the half-edge `chain[0] → chain[1]` without crossing the chain —
/// get duplicates of every chain vertex but the apex, appended to `global`.
/// Returns the second leg (duplicates, then the apex).
fn slit(
    triangles: &mut TiSlice<PanelFace, [PanelVertex; 3]>,
    global: &mut TiVec<PanelVertex, VertexId>,
    chain: &[PanelVertex],
) -> Result<Vec<PanelVertex>, String> {
    if chain.len() < 2 {
        return Err("needs at least one edge".into());
    }
    let k = chain.len() - 1;
    let cut: std::collections::HashSet<MeshEdge<PanelVertex>> =
        chain.windows(2).map(|w| MeshEdge::new(w[0], w[1])).collect();
    let on_chain: HashMap<PanelVertex, usize> = chain[..k].iter().enumerate().map(|(i, &v)| (v, i)).collect();
    let touches = |f: &[PanelVertex; 3]| f.iter().any(|v| on_chain.contains_key(v));
    let start = triangles
        .position(|f| (0..3).any(|j| f[j] == chain[0] && f[(j + 1) % 3] == chain[1]))
        .ok_or_else(|| "its first edge is not in the panel".to_string())?;
    // faces around the chain, and which share a non-chain edge
    let mut by_edge: HashMap<MeshEdge<PanelVertex>, Vec<PanelFace>> = HashMap::new();
    for (fi, f) in triangles.iter_enumerated().filter(|(_, f)| touches(f)) {
        for j in 0..3 {
            by_edge.entry(MeshEdge::new(f[j], f[(j + 1) % 3])).or_default().push(fi);
        }
    }
    let mut side = std::collections::HashSet::from([start]);
    let mut stack = vec![start];
    while let Some(fi) = stack.pop() {
        let f = triangles[fi];
        for j in 0..3 {
            let key = MeshEdge::new(f[j], f[(j + 1) % 3]);
            if cut.contains(&key) {
                continue;
            }
            for &g in by_edge.get(&key).map_or(&[][..], |v| v.as_slice()) {
                if g != fi && side.insert(g) {
                    stack.push(g);
                }
            }
        }
    }
    // the other side must hold faces too, or the chain does not separate anything
    let all: usize = triangles.iter().filter(|f| touches(f)).count();
    if side.len() >= all {
        return Err("the faces around it are not split by it (does it start on the outline?)".into());
    }
    let first_dup = global.len();
    for &v in &chain[..k] {
        global.push(global[v]);
    }
    for &fi in &side {
        for v in triangles[fi].iter_mut() {
            if let Some(&i) = on_chain.get(v) {
                *v = PanelVertex::from(first_dup + i);
            }
        }
    }
    Ok((0..k).map(|i| PanelVertex::from(first_dup + i)).chain(std::iter::once(chain[k])).collect())
}

/// The one boundary loop of a panel's triangles, started at its smallest
/// fine vertex id (a template node: deterministic); the number of loops when
/// there is not exactly one.
pub(crate) fn disc_outline(
    triangles: &TiSlice<PanelFace, [PanelVertex; 3]>,
    global: &TiSlice<PanelVertex, VertexId>,
) -> Result<Vec<PanelVertex>, usize> {
    let loops = boundary_loops(&triangles.raw);
    if loops.len() != 1 {
        return Err(loops.len());
    }
    let mut outline = loops.into_iter().next().unwrap_or_default();
    if let Some(start) = (0..outline.len()).min_by_key(|&k| global[outline[k]]) {
        outline.rotate_left(start);
    }
    Ok(outline)
}

/// The fine chain of a seam's coarse edges, oriented so consecutive edges meet.
fn seam_chain(t: &Template, lineage: &Lineage, seam: &str, edges: &[u32]) -> Result<Vec<VertexId>, PanelError> {
    // coarse node i is fine vertex i (module docs)
    let ends = |e: u32| (VertexId(t.edges[e as usize].start), VertexId(t.edges[e as usize].end));
    let Some(&first) = edges.first() else { return Ok(Vec::new()) };
    let (mut a, mut b) = ends(first);
    if let Some(&second) = edges.get(1) {
        let (c, d) = ends(second);
        if a == c || a == d {
            std::mem::swap(&mut a, &mut b);
        }
    }
    let mut chain = lineage.chain(a, b).unwrap_or_else(|| vec![a, b]);
    let mut tail = b;
    for w in edges.windows(2) {
        let (c, d) = ends(w[1]);
        let next = if c == tail {
            d
        } else if d == tail {
            c
        } else {
            return Err(PanelError::SeamNotChained { seam: seam.to_string(), first: w[0], second: w[1] });
        };
        let piece = lineage.chain(tail, next).unwrap_or_else(|| vec![tail, next]);
        chain.extend_from_slice(&piece[1..]);
        tail = next;
    }
    Ok(chain)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::refine::subdivide::{edge_keys, refine, RefineMesh, RefineOptions, Refined};
    use crate::template::codec::decode;
    use crate::template::format::Relocation;
    use crate::template::library::{builtin, reference_body};
    use glam::DVec3;

    #[test]
    fn lineage_matches_the_split_and_panels_cut_every_template() {
        let body = reference_body().expect("reference body");
        for t in builtin().expect("library") {
            let m0 = decode(&t, &body, Relocation::Eq1Frame).expect("decode");
            let edges: Vec<(u32, u32)> = t.edges.iter().map(|e| (e.start, e.end)).collect();
            let levels = 2;
            let opts = RefineOptions { levels, ..Default::default() };
            let coarse = RefineMesh::from_coarse(&m0, &edges).expect("coarse");
            let Refined { mesh: fine, lineage, .. } =
                refine(coarse, &opts, |_: &mut TiSlice<VertexId, DVec3>, _: &mut TiSlice<VertexId, bool>| {})
                    .expect("refine");
            let (panels, seams) = cut(&t, &fine.positions, &fine.triangles, &lineage).expect("cut");
            // every coarse edge's chain has 2^L + 1 vertices, and its split vertices lie
            // on the fine mesh's edges in order
            let fine_edges: std::collections::HashSet<MeshEdge> = edge_keys(&fine.triangles).into_iter().collect();
            for e in &t.edges {
                let c = lineage.chain(VertexId(e.start), VertexId(e.end)).expect("coarse edge");
                assert_eq!(c.len(), 5);
                assert!(c.windows(2).all(|w| fine_edges.contains(&MeshEdge::new(w[0], w[1]))));
            }
            // panels partition the faces
            let total: usize = panels.iter().map(|p| p.triangles.len()).sum();
            assert_eq!(total, fine.triangles.len(), "{}", t.name);
            for s in &seams {
                assert!(s.chain.len() >= 5, "{}: {}", t.name, s.name);
                // the seam is shared: both panels hold every vertex of the chain
                for &pi in &[s.panel_a, s.panel_b] {
                    assert!(s.chain.iter().all(|&g| panels[pi].local(g).is_some()));
                }
            }
        }
    }

    #[test]
    fn boundary_loops_of_a_quad_and_an_annulus() {
        assert_eq!(boundary_loops(&[[0, 1, 2], [0, 2, 3]]), vec![vec![0, 1, 2, 3]]);
        // a square ring: outer 0..4, inner 4..8
        let ring = [[0, 1, 5], [0, 5, 4], [1, 2, 6], [1, 6, 5], [2, 3, 7], [2, 7, 6], [3, 0, 4], [3, 4, 7]];
        assert_eq!(boundary_loops(&ring).len(), 2);
    }

    #[test]
    fn wrong_face_count_is_named() {
        let t = builtin().expect("library").remove(0);
        let mut one_level = Lineage::new();
        one_level.push_level(Default::default());
        let tris: TiVec<FaceId, _> = vec![[0, 1, 2].map(VertexId)].into();
        let err = cut(&t, TiSlice::from_ref(&[]), &tris, &one_level).unwrap_err();
        assert!(matches!(err, PanelError::FaceCount { fine: 1, levels: 1, .. }), "{err}");
    }
}
