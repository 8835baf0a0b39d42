//! The embedded MakeHuman hm08 body model (CC0): compact binary form,
//! its generator, and its loader.
//!
//! **What is shipped** (`templates/mannequin/hm08.bin.gz`): the skin only
//! (group `body`, vertices 0..13379 of `base.obj`), its quads split into
//! triangles, the sagittal mirror map, the girth rings of `measures.json`,
//! and the morph targets the product uses (macro details, torso, hip,
//! legs, neck, stomach, buttocks, pelvis, breast shape), restricted to skin
//! vertices. Everything is stored losslessly: `base.obj` gives positions
//! to 1e-4 dm and targets give deltas to 1e-3 dm, so positions are `i32`
//! in units of 1e-4 dm and deltas `i16` in units of 1e-3 dm. The file is
//! gzip-compressed.
//!
//! **Reproduce** with `cargo xtask data mannequin` (reads
//! `../shared/makehuman`, see README.md).
//!
//! Layout (little endian, inside gzip):
//! ```text
//! magic "G3DHM08\0" | version u32
//! nv u32 | nv × [i32; 3] positions (1e-4 dm)
//! nt u32 | nt × [u16; 3] triangles
//! nv × u16 mirror vertex
//! nrings u32 | per ring: name (u16 len + utf8) | n u32 | n × u16 vertex ids
//! ntargets u32 | per target: name (u16 len + utf8) | n u32 | n × u16 vertex-id increments
//!     | for x, y, z: n low bytes, then n high bytes of the i16 deltas (1e-3 dm)
//! ```

use std::collections::BTreeMap;
use std::io::{Read, Write};

/// Format version written by [`encode`] and accepted by [`decode`].
pub const FORMAT_VERSION: u32 = 2;
const MAGIC: &[u8; 8] = b"G3DHM08\0";
/// Decimetres per unit of a stored position.
pub const POSITION_UNIT_DM: f64 = 1e-4;
/// Decimetres per unit of a stored target delta.
pub const DELTA_UNIT_DM: f64 = 1e-3;
/// Number of skin vertices in hm08 (group `body`).
pub const SKIN_VERTICES: usize = 13380;

/// The decoded model data, in the file's integer units.
#[derive(Debug, Clone, PartialEq)]
pub struct Hm08Data {
    /// Skin vertex positions (1e-4 dm).
    pub positions: Vec<[i32; 3]>,
    /// Triangles.
    pub triangles: Vec<[u16; 3]>,
    /// Mirror vertex of every skin vertex.
    pub mirror: Vec<u16>,
    /// Girth rings from `measures.json` (name → vertex ids, in order).
    pub rings: BTreeMap<String, Vec<u16>>,
    /// Morph targets (name without `.target.gz`, relative path) → sparse deltas.
    pub targets: BTreeMap<String, Vec<(u16, [i16; 3])>>,
}

/// Problems reading the embedded data or the MakeHuman sources.
#[derive(Debug, thiserror::Error)]
pub enum DataError {
    /// I/O failure (generator only).
    #[error("{path}: {source}")]
    Io {
        /// The file.
        path: String,
        /// The cause.
        source: std::io::Error,
    },
    /// The binary or a source file is malformed.
    #[error("malformed {what}: {detail}")]
    Malformed {
        /// Which file or section.
        what: String,
        /// What is wrong.
        detail: String,
    },
}

impl DataError {
    /// [`DataError::Malformed`] naming `what` (a file or section).
    pub fn malformed(what: &str, detail: impl Into<String>) -> Self {
        DataError::Malformed { what: what.to_owned(), detail: detail.into() }
    }
}

struct Reader<'a> {
    b: &'a [u8],
    at: usize,
}

impl Reader<'_> {
    fn take(&mut self, n: usize) -> Result<&[u8], DataError> {
        let end = self
            .at
            .checked_add(n)
            .filter(|&e| e <= self.b.len())
            .ok_or_else(|| DataError::malformed("hm08.bin", "truncated"))?;
        let s = &self.b[self.at..end];
        self.at = end;
        Ok(s)
    }
    fn u16(&mut self) -> Result<u16, DataError> {
        let s = self.take(2)?;
        Ok(u16::from_le_bytes([s[0], s[1]]))
    }
    fn u32(&mut self) -> Result<u32, DataError> {
        let s = self.take(4)?;
        Ok(u32::from_le_bytes([s[0], s[1], s[2], s[3]]))
    }
    fn i32(&mut self) -> Result<i32, DataError> {
        Ok(self.u32()? as i32)
    }
    fn name(&mut self) -> Result<String, DataError> {
        let n = self.u16()? as usize;
        String::from_utf8(self.take(n)?.to_vec()).map_err(|_| DataError::malformed("hm08.bin", "name is not UTF-8"))
    }
}

/// Decodes the gzip-compressed binary.
pub fn decode(gz: &[u8]) -> Result<Hm08Data, DataError> {
    let mut raw = Vec::new();
    flate2::read::GzDecoder::new(gz)
        .read_to_end(&mut raw)
        .map_err(|e| DataError::malformed("hm08.bin.gz", e.to_string()))?;
    let mut r = Reader { b: &raw, at: 0 };
    if r.take(8)? != MAGIC {
        return Err(DataError::malformed("hm08.bin", "bad magic"));
    }
    let version = r.u32()?;
    if version != FORMAT_VERSION {
        return Err(DataError::malformed("hm08.bin", format!("version {version}, expected {FORMAT_VERSION}")));
    }
    let nv = r.u32()? as usize;
    let mut positions = Vec::with_capacity(nv.min(1 << 20));
    for _ in 0..nv {
        positions.push([r.i32()?, r.i32()?, r.i32()?]);
    }
    let nt = r.u32()? as usize;
    let mut triangles = Vec::with_capacity(nt.min(1 << 20));
    for _ in 0..nt {
        let t = [r.u16()?, r.u16()?, r.u16()?];
        if t.iter().any(|&v| v as usize >= nv) {
            return Err(DataError::malformed("hm08.bin", "triangle index out of range"));
        }
        triangles.push(t);
    }
    let mut mirror = Vec::with_capacity(nv);
    for _ in 0..nv {
        mirror.push(r.u16()?);
    }
    let nrings = r.u32()?;
    let mut rings = BTreeMap::new();
    for _ in 0..nrings {
        let name = r.name()?;
        let n = r.u32()? as usize;
        let mut ids = Vec::with_capacity(n.min(1 << 16));
        for _ in 0..n {
            ids.push(r.u16()?);
        }
        rings.insert(name, ids);
    }
    let ntargets = r.u32()?;
    let mut targets = BTreeMap::new();
    for _ in 0..ntargets {
        let name = r.name()?;
        let n = r.u32()? as usize;
        let mut ids = Vec::with_capacity(n.min(1 << 16));
        let mut prev = 0u16;
        for _ in 0..n {
            prev = prev.wrapping_add(r.u16()?);
            if prev as usize >= nv {
                return Err(DataError::malformed("hm08.bin", format!("target {name} moves vertex {prev}")));
            }
            ids.push(prev);
        }
        let mut cols = [Vec::new(), Vec::new(), Vec::new()];
        for col in &mut cols {
            let lo = r.take(n)?.to_vec();
            let hi = r.take(n)?;
            *col = lo.iter().zip(hi).map(|(&l, &h)| i16::from_le_bytes([l, h])).collect::<Vec<i16>>();
        }
        let d = ids.iter().enumerate().map(|(i, &v)| (v, [cols[0][i], cols[1][i], cols[2][i]])).collect();
        targets.insert(name, d);
    }
    Ok(Hm08Data { positions, triangles, mirror, rings, targets })
}

/// Encodes to the gzip-compressed binary.
pub fn encode(d: &Hm08Data) -> Vec<u8> {
    let mut b = Vec::new();
    b.extend_from_slice(MAGIC);
    b.extend_from_slice(&FORMAT_VERSION.to_le_bytes());
    b.extend_from_slice(&(d.positions.len() as u32).to_le_bytes());
    for p in &d.positions {
        for c in p {
            b.extend_from_slice(&c.to_le_bytes());
        }
    }
    b.extend_from_slice(&(d.triangles.len() as u32).to_le_bytes());
    for t in &d.triangles {
        for c in t {
            b.extend_from_slice(&c.to_le_bytes());
        }
    }
    for m in &d.mirror {
        b.extend_from_slice(&m.to_le_bytes());
    }
    let name = |b: &mut Vec<u8>, s: &str| {
        b.extend_from_slice(&(s.len() as u16).to_le_bytes());
        b.extend_from_slice(s.as_bytes());
    };
    b.extend_from_slice(&(d.rings.len() as u32).to_le_bytes());
    for (k, ids) in &d.rings {
        name(&mut b, k);
        b.extend_from_slice(&(ids.len() as u32).to_le_bytes());
        for v in ids {
            b.extend_from_slice(&v.to_le_bytes());
        }
    }
    b.extend_from_slice(&(d.targets.len() as u32).to_le_bytes());
    for (k, t) in &d.targets {
        name(&mut b, k);
        b.extend_from_slice(&(t.len() as u32).to_le_bytes());
        let mut prev = 0u16;
        for (v, _) in t {
            b.extend_from_slice(&v.wrapping_sub(prev).to_le_bytes());
            prev = *v;
        }
        for k in 0..3 {
            b.extend(t.iter().map(|(_, d)| d[k].to_le_bytes()[0]));
            b.extend(t.iter().map(|(_, d)| d[k].to_le_bytes()[1]));
        }
    }
    let mut enc = flate2::write::GzEncoder::new(Vec::new(), flate2::Compression::best());
    // Writing into a Vec cannot fail.
    let _ = enc.write_all(&b);
    enc.finish().unwrap_or_default()
}
