//! Repair of a scanned triangle soup on input (issue #17, item 1): what a
//! scanner or a phone app hands over, made into a [`TriMesh`] the rest of
//! the pipeline can trust, with every change counted ([`RepairReport`]) —
//! nothing is dropped in silence.
//!
//! # Method
//!
//! In order, on raw positions and `u64` indices (any units: every
//! tolerance is relative to the size of the input):
//! 1. **Weld.** Vertices closer than [`RepairOptions::weld_share`] × the
//!    bounding box's longest side share one (grid hashing; exact
//!    duplicates always merge). Unused vertices are dropped.
//! 2. **Degenerate triangles** — a repeated vertex (after welding), or a
//!    sliver whose height `2A / l` is below [`RepairOptions::sliver_ratio`]
//!    × its longest edge `l`, or below the weld distance (three points
//!    collinear to the precision of the file's coordinates) — are dropped.
//! 3. **Duplicate triangles** (the same three vertices, in either
//!    orientation) are dropped, the first kept.
//! 4. **Components** (connected through shared vertices) whose area is
//!    below [`RepairOptions::min_component_share`] of the whole are
//!    dropped: floating specks, a stray piece of the floor or turntable.
//! 5. **Orientation.** Within each component, faces are made consistent by
//!    a breadth-first walk across manifold edges (an edge of exactly two
//!    faces must be run in opposite directions by them; a face that runs
//!    it the same way is flipped), then a component whose signed volume
//!    `V = Σ_f a·(b × c) / 6` is negative is turned inside out as a whole,
//!    so that normals point out of the body.
//! 6. **Holes** — boundary loops (armpits, crotch, soles, top of the
//!    head: regions a scanner does not see) whose extent (the diagonal of
//!    their bounding box: a ragged outline is much longer than the hole
//!    is wide) is at most [`RepairOptions::max_hole_share`] × the longest
//!    side — are closed by
//!    a fan around the loop's centroid, run against the loop so that the
//!    fill faces agree with their neighbours' orientation. The inside
//!    tests (winding number, depth maps) then see a closed body; a larger
//!    opening is left open and counted ([`RepairReport::holes_left`]).
//!
//! # Failure modes
//!
//! Indices out of range, a non-finite coordinate, and a soup with nothing
//! left after the steps above are [`RepairError`]s naming what is wrong.

use std::collections::VecDeque;

use glam::DVec3;
use rustc_hash::FxHashMap;
use serde::{Deserialize, Serialize};

use super::mesh::{weld_positions, MeshError, TriMesh, VertexId};

/// Knobs of [`repair`]. Every length is a share of the input's longest
/// bounding-box side (the stature of a standing body), because the units
/// are not known yet when it runs.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct RepairOptions {
    /// Vertices closer than this share of the longest side are welded.
    /// Default 1e-6 (2 µm on a 1.8 m body: seams split by UV or normal,
    /// never two real points of a scan).
    pub weld_share: f64,
    /// A triangle whose height over its longest edge is below this is
    /// degenerate. Default 1e-4 (a 5 mm edge with a 0.5 µm height: three
    /// points collinear but for the rounding of single-precision
    /// coordinates, 1e-5 of the edge at a metre from the origin; no
    /// scanner's real triangle is that thin).
    pub sliver_ratio: f64,
    /// A connected component with less than this share of the total area
    /// is dropped. Default 0.01 (a hand is about 2 % of a body's skin).
    pub min_component_share: f64,
    /// A hole whose extent (bounding-box diagonal) is at most this share of
    /// the longest side is closed. Default 0.3 (a whole sole measures
    /// 0.16–0.19 of the stature, the open crown of a head about 0.12; a
    /// larger opening is left open and counted).
    pub max_hole_share: f64,
}

impl Default for RepairOptions {
    fn default() -> Self {
        Self { weld_share: 1e-6, sliver_ratio: 1e-4, min_component_share: 0.01, max_hole_share: 0.3 }
    }
}

/// What [`repair`] changed, counted.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize, Deserialize, utoipa::ToSchema)]
pub struct RepairReport {
    /// Vertices and triangles as read.
    pub vertices_in: usize,
    /// Triangles as read.
    pub triangles_in: usize,
    /// Vertices merged into another by welding.
    pub vertices_welded: usize,
    /// Triangles dropped as degenerate (repeated vertex or no area).
    pub degenerate_dropped: usize,
    /// Triangles dropped as duplicates of another.
    pub duplicates_dropped: usize,
    /// Connected components dropped as too small.
    pub components_dropped: usize,
    /// Triangles of those components.
    pub component_triangles_dropped: usize,
    /// Triangles flipped to agree with their neighbours or to face out.
    pub triangles_reoriented: usize,
    /// Holes closed.
    pub holes_filled: usize,
    /// Openings left open (longer than the hole limit).
    pub holes_left: usize,
    /// Triangles added to close the holes: the last ones of the mesh.
    pub fill_triangles: usize,
    /// Vertices of the repaired mesh.
    pub vertices_out: usize,
    /// Triangles of the repaired mesh.
    pub triangles_out: usize,
}

impl RepairReport {
    /// Per triangle of the repaired mesh: whether it was read (true) or
    /// added to close a hole (false).
    pub fn read_faces(&self) -> Vec<bool> {
        let read = self.triangles_out - self.fill_triangles;
        (0..self.triangles_out).map(|f| f < read).collect()
    }

    /// Whether anything was changed.
    pub fn changed(&self) -> bool {
        self.vertices_welded
            + self.degenerate_dropped
            + self.duplicates_dropped
            + self.components_dropped
            + self.triangles_reoriented
            + self.holes_filled
            > 0
    }
}

/// Why a soup could not be repaired into a mesh.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum RepairError {
    /// A triangle names a vertex that does not exist, or a coordinate is
    /// not finite, or there is nothing to read.
    #[error(transparent)]
    Mesh(#[from] MeshError),
    /// Every triangle was degenerate, duplicate or in a dropped component.
    #[error("nothing is left of the mesh after repair: {triangles} triangles were all degenerate or duplicates")]
    NothingLeft {
        /// Triangles read.
        triangles: usize,
    },
}

/// Repairs `positions` / `triangles` (module docs).
///
/// # Errors
/// [`RepairError`].
pub fn repair(
    positions: &[DVec3],
    triangles: &[[u64; 3]],
    opts: &RepairOptions,
) -> Result<(TriMesh, RepairReport), RepairError> {
    let mut report = RepairReport { vertices_in: positions.len(), triangles_in: triangles.len(), ..Default::default() };
    if positions.is_empty() || triangles.is_empty() {
        return Err(MeshError::Empty { vertices: positions.len(), triangles: triangles.len() }.into());
    }
    if let Some(v) = positions.iter().position(|p| !p.is_finite()) {
        return Err(MeshError::NonFinite { vertex: u32::try_from(v).unwrap_or(u32::MAX) }.into());
    }
    let n = positions.len() as u64;
    for (f, t) in triangles.iter().enumerate() {
        if let Some(&i) = t.iter().find(|&&i| i >= n) {
            let face = u32::try_from(f).map_err(|_| MeshError::TooLarge { count: triangles.len() })?;
            return Err(MeshError::IndexOutOfRange { face, index: i, count: positions.len() }.into());
        }
    }
    if positions.len() > u32::MAX as usize || triangles.len() > u32::MAX as usize {
        return Err(MeshError::TooLarge { count: positions.len().max(triangles.len()) }.into());
    }
    let (lo, hi) = positions.iter().fold((DVec3::INFINITY, DVec3::NEG_INFINITY), |(lo, hi), &p| (lo.min(p), hi.max(p)));
    let side = (hi - lo).max_element().max(f64::MIN_POSITIVE);

    // 1. weld
    let weld = opts.weld_share * side;
    let (welded, remap) = weld_positions(positions, weld);
    // 2.-3. degenerate and duplicate triangles
    let mut tris: Vec<[u32; 3]> = Vec::with_capacity(triangles.len());
    let mut seen: FxHashMap<[u32; 3], ()> = FxHashMap::default();
    for t in triangles {
        let t = t.map(|i| remap[i as usize]);
        if t[0] == t[1] || t[1] == t[2] || t[0] == t[2] {
            report.degenerate_dropped += 1;
            continue;
        }
        let [a, b, c] = t.map(|i| welded[i as usize]);
        let longest = a.distance(b).max(b.distance(c)).max(c.distance(a));
        // height = 2A / l below r·l, or below the weld distance (precision of the coordinates)
        if (b - a).cross(c - a).length() <= longest * (opts.sliver_ratio * longest).max(weld) {
            report.degenerate_dropped += 1;
            continue;
        }
        let mut key = t;
        key.sort_unstable();
        if seen.insert(key, ()).is_some() {
            report.duplicates_dropped += 1;
            continue;
        }
        tris.push(t);
    }
    // 4. small components
    let comp = components(welded.len(), &tris);
    let count = comp.iter().map(|&c| c as usize + 1).max().unwrap_or(0);
    let mut area = vec![0.0; count];
    let mut faces = vec![0usize; count];
    for (t, &c) in tris.iter().zip(&comp) {
        let [a, b, c2] = t.map(|i| welded[i as usize]);
        area[c as usize] += 0.5 * (b - a).cross(c2 - a).length();
        faces[c as usize] += 1;
    }
    let total: f64 = area.iter().sum();
    let keep: Vec<bool> = area.iter().map(|&a| a >= opts.min_component_share * total).collect();
    for (c, &k) in keep.iter().enumerate() {
        if !k {
            report.components_dropped += 1;
            report.component_triangles_dropped += faces[c];
        }
    }
    let (mut tris, comp): (Vec<[u32; 3]>, Vec<u32>) =
        tris.into_iter().zip(comp).filter(|(_, c)| keep[*c as usize]).unzip();
    if tris.is_empty() {
        return Err(RepairError::NothingLeft { triangles: triangles.len() });
    }
    // 5. orientation
    let (flipped, boundary) = orient(&welded, &mut tris, &comp);
    report.triangles_reoriented = flipped;
    // 6. holes
    let (mut pos, mut tris, map) = compact(&welded, tris);
    let limit = opts.max_hole_share * side;
    let boundary = boundary.into_iter().map(|(a, b)| (map[a as usize], map[b as usize])).collect();
    for lp in loops_of(boundary) {
        let ring: Vec<DVec3> = lp.iter().map(|&v| pos[v as usize]).collect();
        let (lo, hi) = ring.iter().fold((DVec3::INFINITY, DVec3::NEG_INFINITY), |(lo, hi), &p| (lo.min(p), hi.max(p)));
        if lp.len() < 3 || lo.distance(hi) > limit {
            report.holes_left += 1;
            continue;
        }
        let centre = ring.iter().sum::<DVec3>() / ring.len() as f64;
        let c = pos.len() as u32;
        pos.push(centre);
        // the loop runs along its faces' orientation: the fill runs against it
        for i in 0..lp.len() {
            tris.push([lp[(i + 1) % lp.len()], lp[i], c]);
        }
        report.fill_triangles += lp.len();
        report.holes_filled += 1;
    }
    report.vertices_welded = positions.len() - welded.len();
    report.vertices_out = pos.len();
    report.triangles_out = tris.len();
    let tris = tris.into_iter().map(|t| t.map(VertexId)).collect();
    Ok((TriMesh::new(pos, tris)?, report))
}

/// Union–find root with path halving.
fn root(parent: &mut [u32], mut v: u32) -> u32 {
    while parent[v as usize] != v {
        parent[v as usize] = parent[parent[v as usize] as usize];
        v = parent[v as usize];
    }
    v
}

/// The component of each triangle (connected through shared vertices),
/// numbered from 0 in order of first appearance.
fn components(vertices: usize, tris: &[[u32; 3]]) -> Vec<u32> {
    let mut parent: Vec<u32> = (0..vertices as u32).collect();
    for t in tris {
        let r = root(&mut parent, t[0]);
        for &v in &t[1..] {
            let s = root(&mut parent, v);
            if s != r {
                parent[s as usize] = r;
            }
        }
    }
    let mut number: FxHashMap<u32, u32> = FxHashMap::default();
    tris.iter()
        .map(|t| {
            let r = root(&mut parent, t[0]);
            let next = number.len() as u32;
            *number.entry(r).or_insert(next)
        })
        .collect()
}

/// Each face's neighbour across its edge `k` (from corner `k` to `k + 1`)
/// where that edge is manifold (exactly two faces), `u32::MAX` elsewhere;
/// and the boundary edges (one face) as `(face, k)`.
fn adjacency(tris: &[[u32; 3]]) -> (Vec<[u32; 3]>, Vec<(u32, u8)>) {
    // (undirected edge, face, k) sorted: each edge's uses a run
    let mut uses: Vec<((u32, u32), u32, u8)> = Vec::with_capacity(3 * tris.len());
    for (f, t) in tris.iter().enumerate() {
        for k in 0..3 {
            let (a, b) = (t[k], t[(k + 1) % 3]);
            uses.push(((a.min(b), a.max(b)), f as u32, k as u8));
        }
    }
    uses.sort_unstable();
    let mut next = vec![[u32::MAX; 3]; tris.len()];
    let mut boundary = Vec::new();
    let mut i = 0;
    while i < uses.len() {
        let mut j = i + 1;
        while j < uses.len() && uses[j].0 == uses[i].0 {
            j += 1;
        }
        match j - i {
            1 => boundary.push((uses[i].1, uses[i].2)),
            2 => {
                let ((_, f, k), (_, g, l)) = (uses[i], uses[i + 1]);
                next[f as usize][k as usize] = g;
                next[g as usize][l as usize] = f;
            }
            _ => {}
        }
        i = j;
    }
    (next, boundary)
}

/// Makes each component's faces agree across manifold edges and face out
/// (module docs, step 5); returns how many faces it flipped, and the
/// boundary edges as directed half-edges of the faces as they now run.
fn orient(pos: &[DVec3], tris: &mut [[u32; 3]], comp: &[u32]) -> (usize, Vec<(u32, u32)>) {
    let (next, boundary) = adjacency(tris);
    let runs = |t: &[u32; 3], a: u32, b: u32| (0..3).any(|k| t[k] == a && t[(k + 1) % 3] == b);
    let mut flipped = vec![false; tris.len()];
    let mut visited = vec![false; tris.len()];
    let mut queue = VecDeque::new();
    for seed in 0..tris.len() {
        if visited[seed] {
            continue;
        }
        visited[seed] = true;
        queue.push_back(seed);
        while let Some(f) = queue.pop_front() {
            let t = tris[f];
            // `next` is indexed by the edges as the faces were read; a flip swaps corners 1 and
            // 2, which keeps edge {t0, t1}'s neighbour under k = 0 only for unflipped faces
            let edges: [u32; 3] = if flipped[f] { [next[f][2], next[f][1], next[f][0]] } else { next[f] };
            for (k, &g) in edges.iter().enumerate() {
                let g = g as usize;
                if g == u32::MAX as usize || visited[g] {
                    continue;
                }
                let (a, b) = (t[k], t[(k + 1) % 3]);
                visited[g] = true;
                if runs(&tris[g], a, b) {
                    tris[g].swap(1, 2);
                    flipped[g] = !flipped[g];
                }
                queue.push_back(g);
            }
        }
    }
    // each component facing out: positive signed volume about its centroid
    let count = comp.iter().map(|&c| c as usize + 1).max().unwrap_or(0);
    let mut centre = vec![DVec3::ZERO; count];
    let mut weight = vec![0.0; count];
    for (t, &c) in tris.iter().zip(comp) {
        for &v in t {
            centre[c as usize] += pos[v as usize];
            weight[c as usize] += 1.0;
        }
    }
    let mut volume = vec![0.0; count];
    for (t, &c) in tris.iter().zip(comp) {
        let o = centre[c as usize] / weight[c as usize];
        let [a, b, d] = t.map(|v| pos[v as usize] - o);
        volume[c as usize] += a.dot(b.cross(d)) / 6.0;
    }
    for (f, t) in tris.iter_mut().enumerate() {
        if volume[comp[f] as usize] < 0.0 {
            t.swap(1, 2);
            flipped[f] = !flipped[f];
        }
    }
    // the boundary edges, each run as its face now runs it
    let half_edges = boundary
        .into_iter()
        .map(|(f, k)| {
            let t = tris[f as usize];
            let k = if flipped[f as usize] { [2, 1, 0][k as usize] } else { k as usize };
            (t[k], t[(k + 1) % 3])
        })
        .collect();
    (flipped.iter().filter(|&&x| x).count(), half_edges)
}

/// The boundary half-edges chained into loops, each run along its faces'
/// orientation (as [`super::mesh::boundary_loops`], from the half-edges alone).
fn loops_of(mut half_edges: Vec<(u32, u32)>) -> Vec<Vec<u32>> {
    half_edges.sort_unstable();
    let mut used = vec![false; half_edges.len()];
    let mut loops = Vec::new();
    for s in 0..half_edges.len() {
        if used[s] {
            continue;
        }
        used[s] = true;
        let (start, mut at) = half_edges[s];
        let mut lp = vec![start];
        while at != start {
            lp.push(at);
            // an unused half-edge leaving `at`
            let from = half_edges.partition_point(|e| e.0 < at);
            let Some(i) = (from..half_edges.len()).take_while(|&i| half_edges[i].0 == at).find(|&i| !used[i]) else {
                break;
            };
            used[i] = true;
            at = half_edges[i].1;
        }
        loops.push(lp);
    }
    loops
}

/// Drops unused vertices, keeping the others in their order; and the old
/// index → new index map.
fn compact(pos: &[DVec3], tris: Vec<[u32; 3]>) -> (Vec<DVec3>, Vec<[u32; 3]>, Vec<u32>) {
    let mut used = vec![false; pos.len()];
    for t in &tris {
        for &v in t {
            used[v as usize] = true;
        }
    }
    let mut map = vec![u32::MAX; pos.len()];
    let mut out = Vec::with_capacity(pos.len());
    for (i, &p) in pos.iter().enumerate() {
        if used[i] {
            map[i] = out.len() as u32;
            out.push(p);
        }
    }
    let tris = tris.into_iter().map(|t| t.map(|v| map[v as usize])).collect();
    (out, tris, map)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geom::mesh::boundary_loops;
    use crate::geom::winding::{WindingOptions, WindingTree};

    fn raw(mesh: &TriMesh) -> (Vec<DVec3>, Vec<[u64; 3]>) {
        (mesh.positions().to_vec(), mesh.triangles().iter().map(|t| t.map(|v| u64::from(v.0))).collect())
    }

    /// A closed unit UV sphere, facing out.
    fn uv_sphere(rings: usize, sectors: usize) -> TriMesh {
        use std::f64::consts::PI;
        let mut pos = vec![DVec3::Y];
        for i in 1..rings {
            let phi = PI * i as f64 / rings as f64;
            for j in 0..sectors {
                let th = 2.0 * PI * j as f64 / sectors as f64;
                pos.push(DVec3::new(phi.sin() * th.cos(), phi.cos(), -phi.sin() * th.sin()));
            }
        }
        pos.push(-DVec3::Y);
        let south = (pos.len() - 1) as u64;
        let idx = |i: usize, j: usize| (1 + (i - 1) * sectors + j % sectors) as u64;
        let mut tris = Vec::new();
        for j in 0..sectors {
            tris.push([0, idx(1, j), idx(1, j + 1)]);
            tris.push([south, idx(rings - 1, j + 1), idx(rings - 1, j)]);
        }
        for i in 1..rings - 1 {
            for j in 0..sectors {
                tris.push([idx(i, j), idx(i + 1, j + 1), idx(i, j + 1)]);
                tris.push([idx(i, j), idx(i + 1, j), idx(i + 1, j + 1)]);
            }
        }
        TriMesh::from_raw(pos, &tris).expect("a valid sphere")
    }

    fn closed(mesh: &TriMesh) -> bool {
        boundary_loops(mesh.triangles()).is_empty()
    }

    #[test]
    fn a_clean_closed_mesh_is_left_as_it_is() {
        let ico = TriMesh::icosahedron();
        let (p, t) = raw(&ico);
        let (m, r) = repair(&p, &t, &RepairOptions::default()).expect("repairs");
        assert!(!r.changed(), "{r:?}");
        assert_eq!((m.vertex_count(), m.face_count()), (12, 20));
        assert_eq!(m, ico);
    }

    #[test]
    fn split_vertices_degenerate_and_duplicate_triangles_are_counted_and_gone() {
        let ico = TriMesh::icosahedron();
        let (mut p, mut t) = raw(&ico);
        // split vertex 0: faces of the first half use a copy
        p.push(p[0]);
        let copy = (p.len() - 1) as u64;
        for tri in t.iter_mut().take(10) {
            for i in tri.iter_mut() {
                if *i == 0 {
                    *i = copy;
                }
            }
        }
        t.push([1, 1, 2]); // repeated vertex
        t.push([0, copy, 3]); // repeated after welding
        t.push(t[4]); // duplicate
        let rev = [t[5][0], t[5][2], t[5][1]];
        t.push(rev); // duplicate, other orientation
        let (m, r) = repair(&p, &t, &RepairOptions::default()).expect("repairs");
        assert_eq!(r.vertices_welded, 1);
        assert_eq!(r.degenerate_dropped, 2);
        assert_eq!(r.duplicates_dropped, 2);
        assert_eq!((m.vertex_count(), m.face_count()), (12, 20));
        assert!(closed(&m));
    }

    #[test]
    fn flipped_faces_and_an_inside_out_mesh_face_out_again() {
        let ico = TriMesh::icosahedron();
        let (p, mut t) = raw(&ico);
        for tri in t.iter_mut().step_by(3) {
            tri.swap(1, 2);
        }
        let (m, r) = repair(&p, &t, &RepairOptions::default()).expect("repairs");
        assert_eq!(r.triangles_reoriented, 7);
        assert_eq!(m, ico);
        let inverted: Vec<[u64; 3]> = raw(&ico).1.iter().map(|t| [t[0], t[2], t[1]]).collect();
        let (m, r) = repair(&p, &inverted, &RepairOptions::default()).expect("repairs");
        assert_eq!(r.triangles_reoriented, 20);
        assert_eq!(m, ico);
    }

    #[test]
    fn a_small_floating_component_is_dropped_and_a_large_one_kept() {
        let ico = TriMesh::icosahedron();
        let (mut p, mut t) = raw(&ico);
        let add = |p: &mut Vec<DVec3>, t: &mut Vec<[u64; 3]>, scale: f64, at: DVec3| {
            let base = p.len() as u64;
            p.extend(ico.positions().iter().map(|&q| q * scale + at));
            t.extend(ico.triangles().iter().map(|f| f.map(|v| u64::from(v.0) + base)));
        };
        add(&mut p, &mut t, 0.05, DVec3::new(5.0, 0.0, 0.0));
        add(&mut p, &mut t, 0.9, DVec3::new(-5.0, 0.0, 0.0));
        let (m, r) = repair(&p, &t, &RepairOptions::default()).expect("repairs");
        assert_eq!((r.components_dropped, r.component_triangles_dropped), (1, 20));
        assert_eq!((m.vertex_count(), m.face_count()), (24, 40));
    }

    #[test]
    fn holes_are_closed_facing_out_and_the_inside_test_agrees_with_the_whole_mesh() {
        // a UV sphere, cut open at both poles
        let sphere = uv_sphere(24, 32);
        let (p, t) = raw(&sphere);
        let cut: Vec<[u64; 3]> =
            t.iter().copied().filter(|f| f.iter().all(|&v| p[v as usize].normalize().y.abs() < 0.995)).collect();
        assert!(cut.len() < t.len());
        let (m, r) = repair(&p, &cut, &RepairOptions::default()).expect("repairs");
        assert_eq!((r.holes_filled, r.holes_left), (2, 0));
        assert!(closed(&m));
        assert_eq!(r.triangles_reoriented, 0, "the fill agrees with the sphere's orientation");
        let whole = WindingTree::new(&sphere, &WindingOptions::default());
        let repaired = WindingTree::new(&m, &WindingOptions::default());
        let mut agree = 0;
        let total = 2000;
        for i in 0..total {
            let s = i as f64 / total as f64;
            let q = DVec3::new((s * 97.0).sin(), (s * 61.0).cos(), (s * 37.0).sin()) * 1.1 * (0.3 + 0.7 * s);
            agree += usize::from(whole.is_inside(q) == repaired.is_inside(q));
        }
        assert!(agree as f64 >= 0.99 * total as f64, "{agree} of {total}");
        assert!(repaired.winding_number(DVec3::new(0.0, 0.95, 0.0)) > 0.5, "inside at a filled pole");
        // a hole longer than the limit stays open, counted
        let strict = RepairOptions { max_hole_share: 0.05, ..Default::default() };
        let (m, r) = repair(&p, &cut, &strict).expect("repairs");
        assert_eq!((r.holes_filled, r.holes_left), (0, 2));
        assert_eq!(boundary_loops(m.triangles()).len(), 2);
    }

    #[test]
    fn bad_input_is_named() {
        let p = vec![DVec3::ZERO, DVec3::X, DVec3::Y];
        assert!(matches!(
            repair(&p, &[[0, 1, 7]], &RepairOptions::default()),
            Err(RepairError::Mesh(MeshError::IndexOutOfRange { face: 0, index: 7, .. }))
        ));
        let q = vec![DVec3::ZERO, DVec3::X, DVec3::splat(f64::NAN)];
        assert!(matches!(
            repair(&q, &[[0, 1, 2]], &RepairOptions::default()),
            Err(RepairError::Mesh(MeshError::NonFinite { vertex: 2 }))
        ));
        assert_eq!(
            repair(&p, &[[0, 1, 1], [0, 0, 0]], &RepairOptions::default()),
            Err(RepairError::NothingLeft { triangles: 2 })
        );
    }
}
