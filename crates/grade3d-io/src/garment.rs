//! A designed garment's file (issue #18, item 1): GLB/glTF with one mesh
//! (or primitive) per pattern piece ([`crate::gltf::read_parts`]), or OBJ
//! with one `g`/`o` group per piece ([`crate::obj::read_obj_panels`]),
//! told apart by their first bytes (the GLB magic `glTF`, a glTF JSON's
//! `{`; anything else is read as OBJ text).
//!
//! Failure modes: [`GarmentFileError`] — the reader's own error, OBJ that
//! is not UTF-8.

use glam::DVec3;
use grade3d_core::template::garment_panels::PanelMesh;

use crate::gltf::{read_parts, GltfError, GltfReadOptions};
use crate::obj::{read_obj_panels, ObjError};

/// Why a garment file could not be read.
#[derive(Debug, thiserror::Error)]
pub enum GarmentFileError {
    /// The GLB/glTF reader's error.
    #[error("garment glTF: {0}")]
    Gltf(#[from] GltfError),
    /// The OBJ reader's error.
    #[error("garment OBJ: {0}")]
    Obj(#[from] ObjError),
    /// OBJ text that is not UTF-8.
    #[error("garment OBJ is not UTF-8 text (nor a GLB: no `glTF` magic)")]
    NotUtf8,
    /// A piece's vertex index does not fit the panel's 32-bit indices.
    #[error("garment piece `{piece}` has more vertices than 32-bit indices hold")]
    TooLarge {
        /// The piece.
        piece: String,
    },
}

/// Which format a garment file is in.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum GarmentFormat {
    /// GLB or glTF JSON.
    Gltf,
    /// Wavefront OBJ.
    Obj,
}

/// The format of `bytes` (module docs).
pub fn garment_format(bytes: &[u8]) -> GarmentFormat {
    let first = bytes.iter().find(|b| !b.is_ascii_whitespace());
    if bytes.starts_with(b"glTF") || first == Some(&b'{') {
        GarmentFormat::Gltf
    } else {
        GarmentFormat::Obj
    }
}

/// Reads a garment's pieces, in the file's units.
///
/// # Errors
/// [`GarmentFileError`].
pub fn read_garment(bytes: &[u8], opts: &GltfReadOptions) -> Result<Vec<PanelMesh>, GarmentFileError> {
    match garment_format(bytes) {
        GarmentFormat::Gltf => read_parts(bytes, opts)?
            .into_iter()
            .map(|p| {
                let tooc = || GarmentFileError::TooLarge { piece: p.name.clone() };
                let triangles = p
                    .triangles
                    .iter()
                    .map(|t| {
                        let c = t.map(u32::try_from);
                        match c {
                            [Ok(a), Ok(b), Ok(c)] => Ok([a, b, c]),
                            _ => Err(tooc()),
                        }
                    })
                    .collect::<Result<Vec<_>, _>>()?;
                Ok(PanelMesh { name: p.name.clone(), positions: p.positions.clone(), triangles, uv: p.uv.clone() })
            })
            .collect(),
        GarmentFormat::Obj => {
            let text = std::str::from_utf8(bytes).map_err(|_| GarmentFileError::NotUtf8)?;
            Ok(read_obj_panels(text)?)
        }
    }
}

/// `pieces` with every position scaled by `factor` (a unit to metres).
pub fn scaled(pieces: Vec<PanelMesh>, factor: f64) -> Vec<PanelMesh> {
    pieces
        .into_iter()
        .map(|p| PanelMesh { positions: p.positions.iter().map(|&q: &DVec3| q * factor).collect(), ..p })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn formats_by_first_bytes() {
        assert_eq!(garment_format(b"glTF\x02\0\0\0"), GarmentFormat::Gltf);
        assert_eq!(garment_format(b"  {\"asset\":{}}"), GarmentFormat::Gltf);
        assert_eq!(garment_format(b"# obj\nv 0 0 0\n"), GarmentFormat::Obj);
    }

    #[test]
    fn obj_pieces_and_refusals() {
        let obj = "o front\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\no back\nv 0 0 1\nv 1 0 1\nv 0 1 1\nf 4 5 6\n";
        let p = read_garment(obj.as_bytes(), &GltfReadOptions::default()).unwrap();
        assert_eq!(p.iter().map(|p| p.name.as_str()).collect::<Vec<_>>(), ["front", "back"]);
        let mm = scaled(p, 1e-3);
        assert_eq!(mm[1].positions[0], DVec3::new(0.0, 0.0, 1e-3));
        assert!(matches!(
            read_garment(&[0xff, 0xfe, 0x00], &GltfReadOptions::default()),
            Err(GarmentFileError::NotUtf8)
        ));
        assert!(matches!(read_garment(b"glTF\x02\0\0\0", &GltfReadOptions::default()), Err(GarmentFileError::Gltf(_))));
    }

    /// A GLB written with two meshes reads back as two named pieces.
    #[test]
    fn glb_one_piece_per_mesh() {
        let skirt = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../fixtures/garments/helper-skirt.glb");
        let p = read_garment(&std::fs::read(skirt).unwrap(), &GltfReadOptions::default()).unwrap();
        assert_eq!(p.len(), 1);
        assert_eq!(p[0].triangles.len(), 1368);
    }
}
