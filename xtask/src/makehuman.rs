//! The generator of the embedded hm08 data (`cargo xtask data mannequin`,
//! `data garments`): reads a MakeHuman folder from disk and builds the
//! [`Hm08Data`] the core's [`grade3d_core::mannequin::data::encode`] packs.
//! Generator only, never used at run time; file I/O lives here, not in the
//! core (issue #16).

use std::collections::BTreeMap;
use std::io::Read;
use std::path::Path;

use grade3d_core::mannequin::data::{DataError, Hm08Data, DELTA_UNIT_DM, POSITION_UNIT_DM, SKIN_VERTICES};

/// Target folders (under `targets/`) that are shipped, and a filter on
/// the file name within each.
const SHIPPED: &[(&str, &str)] = &[
    ("macrodetails", ""),
    ("macrodetails/height", ""),
    ("macrodetails/proportions", ""),
    ("torso", ""),
    ("hip", ""),
    ("legs", ""),
    ("neck", ""),
    ("stomach", ""),
    ("buttocks", ""),
    ("pelvis", ""),
    ("breast", "breast-"),
    ("arms", "measure-"),
];

fn read_text(path: &Path) -> Result<String, DataError> {
    std::fs::read_to_string(path).map_err(|source| DataError::Io { path: path.display().to_string(), source })
}

fn fixed(x: f64, unit: f64, what: &str) -> Result<f64, DataError> {
    let q = x / unit;
    if (q - q.round()).abs() > 1e-3 {
        return Err(DataError::malformed(
            what,
            format!("{x} is not a multiple of {unit}: the encoding would lose precision"),
        ));
    }
    Ok(q.round())
}

/// Builds [`Hm08Data`] from a MakeHuman folder (`base.obj`, `hm08.mirror`,
/// `measures.json`, `targets/`). Generator only; not used at run time.
pub fn from_makehuman(dir: &Path) -> Result<Hm08Data, DataError> {
    let obj = parse_obj(&read_text(&dir.join("base.obj"))?)?;
    let mut positions = Vec::with_capacity(SKIN_VERTICES);
    for c in obj.vertices.iter().take(SKIN_VERTICES) {
        let mut p = [0i32; 3];
        for k in 0..3 {
            p[k] = fixed(c[k], POSITION_UNIT_DM, "base.obj")? as i32;
        }
        positions.push(p);
    }
    let mut triangles = Vec::new();
    for (group, ids) in &obj.faces {
        if group != "body" {
            continue;
        }
        if ids.iter().any(|&i| i >= SKIN_VERTICES) {
            return Err(DataError::malformed("base.obj", format!("body face {ids:?} leaves the skin")));
        }
        for k in 1..ids.len() - 1 {
            triangles.push([ids[0] as u16, ids[k] as u16, ids[k + 1] as u16]);
        }
    }
    if positions.len() != SKIN_VERTICES {
        return Err(DataError::malformed("base.obj", format!("{} skin vertices", positions.len())));
    }
    let mut mirror = vec![0u16; SKIN_VERTICES];
    for line in read_text(&dir.join("hm08.mirror"))?.lines() {
        let f: Vec<usize> = line.split_whitespace().take(2).filter_map(|s| s.parse().ok()).collect();
        if let [a, b] = f[..] {
            if a < SKIN_VERTICES {
                if b >= SKIN_VERTICES {
                    return Err(DataError::malformed("hm08.mirror", format!("skin vertex {a} mirrors to {b}")));
                }
                mirror[a] = b as u16;
            }
        }
    }
    let measures: serde_json::Value = serde_json::from_str(&read_text(&dir.join("measures.json"))?)
        .map_err(|e| DataError::malformed("measures.json", e.to_string()))?;
    let mut rings = BTreeMap::new();
    if let Some(m) = measures.get("measures").and_then(|m| m.as_object()) {
        for (k, v) in m {
            let ids: Vec<u16> =
                v.as_array().into_iter().flatten().filter_map(|x| x.as_u64()).map(|x| x as u16).collect();
            rings.insert(k.clone(), ids);
        }
    }
    let mut targets = BTreeMap::new();
    for (folder, prefix) in SHIPPED {
        let path = dir.join("targets").join(folder);
        let mut entries: Vec<_> = std::fs::read_dir(&path)
            .map_err(|source| DataError::Io { path: path.display().to_string(), source })?
            .filter_map(|e| e.ok())
            .map(|e| e.file_name().to_string_lossy().into_owned())
            .filter(|n| n.ends_with(".target.gz") && n.starts_with(prefix))
            .collect();
        entries.sort();
        for file in entries {
            let bytes = std::fs::read(path.join(&file))
                .map_err(|source| DataError::Io { path: path.join(&file).display().to_string(), source })?;
            let mut text = String::new();
            flate2::read::GzDecoder::new(&bytes[..])
                .read_to_string(&mut text)
                .map_err(|e| DataError::malformed(&file, e.to_string()))?;
            let mut deltas = Vec::new();
            for line in text.lines().filter(|l| !l.starts_with('#') && !l.trim().is_empty()) {
                let f: Vec<&str> = line.split_whitespace().collect();
                if f.len() < 4 {
                    return Err(DataError::malformed(&file, format!("bad line `{line}`")));
                }
                let v: usize =
                    f[0].parse().map_err(|_| DataError::malformed(&file, format!("bad index in `{line}`")))?;
                if v >= SKIN_VERTICES {
                    continue;
                }
                let mut d = [0i16; 3];
                for k in 0..3 {
                    let x: f64 =
                        f[k + 1].parse().map_err(|_| DataError::malformed(&file, format!("bad delta in `{line}`")))?;
                    let q = fixed(x, DELTA_UNIT_DM, &file)?;
                    if q.abs() > f64::from(i16::MAX) {
                        return Err(DataError::malformed(&file, format!("delta {x} out of range")));
                    }
                    d[k] = q as i16;
                }
                if d != [0, 0, 0] {
                    deltas.push((v as u16, d));
                }
            }
            let name = format!("{folder}/{}", file.trim_end_matches(".target.gz"));
            targets.insert(name, deltas);
        }
    }
    Ok(Hm08Data { positions, triangles, mirror, rings, targets })
}

/// The vertices and grouped faces of an OBJ file (0-based vertex ids).
struct Obj {
    vertices: Vec<[f64; 3]>,
    faces: Vec<(String, Vec<usize>)>,
}

fn parse_obj(text: &str) -> Result<Obj, DataError> {
    let mut obj = Obj { vertices: Vec::new(), faces: Vec::new() };
    let mut group = String::new();
    for line in text.lines() {
        let mut it = line.split_whitespace();
        match it.next() {
            Some("v") => {
                let c: Vec<f64> = it.take(3).filter_map(|s| s.parse().ok()).collect();
                let [x, y, z] = c[..] else {
                    return Err(DataError::malformed("base.obj", format!("bad vertex line `{line}`")));
                };
                obj.vertices.push([x, y, z]);
            }
            Some("g") => group = it.next().unwrap_or("").to_owned(),
            Some("f") => {
                let ids: Vec<usize> = it
                    .filter_map(|s| s.split('/').next()?.parse::<usize>().ok())
                    .map(|i| i.saturating_sub(1))
                    .collect();
                if ids.len() < 3 {
                    return Err(DataError::malformed("base.obj", format!("bad face `{line}`")));
                }
                obj.faces.push((group.clone(), ids));
            }
            _ => {}
        }
    }
    Ok(obj)
}

/// One face group of `base.obj` (e.g. `helper-skirt`) as a compact
/// triangle mesh in metres: its vertices renumbered in first-use order,
/// quads split along their first diagonal. Generator only.
pub fn obj_group(dir: &Path, group: &str) -> Result<(Vec<glam::DVec3>, Vec<[u32; 3]>), DataError> {
    let obj = parse_obj(&read_text(&dir.join("base.obj"))?)?;
    let mut remap: BTreeMap<usize, u32> = BTreeMap::new();
    let mut order = Vec::new();
    let mut tris = Vec::new();
    for (g, ids) in &obj.faces {
        if g != group {
            continue;
        }
        let mut local = Vec::with_capacity(ids.len());
        for &i in ids {
            let next = remap.len() as u32;
            local.push(*remap.entry(i).or_insert_with(|| {
                order.push(i);
                next
            }));
        }
        for k in 1..local.len() - 1 {
            tris.push([local[0], local[k], local[k + 1]]);
        }
    }
    if tris.is_empty() {
        return Err(DataError::malformed("base.obj", format!("no faces in group `{group}`")));
    }
    let mut positions = Vec::with_capacity(order.len());
    for i in order {
        let c = obj
            .vertices
            .get(i)
            .ok_or_else(|| DataError::malformed("base.obj", format!("face refers to vertex {i}")))?;
        positions.push(glam::DVec3::from_array(*c) * 0.1);
    }
    Ok((positions, tris))
}
