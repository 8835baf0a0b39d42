//! Fixture loading shared by the integration tests.

use std::path::{Path, PathBuf};

use grade3d::body::derive::Landmarks;
use grade3d::geom::mesh::TriMesh;
use grade3d::io::gltf::{read_mesh, GltfReadOptions};
use grade3d::io::landmarks::parse_landmarks;

/// The fixtures folder.
pub fn fixtures() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("fixtures")
}

/// Every fixture body: (name, mesh, landmarks).
pub fn fixture_bodies() -> Vec<(String, TriMesh, Landmarks)> {
    let mut out = Vec::new();
    for sub in ["bodies", "astm"] {
        let dir = fixtures().join(sub);
        let mut names: Vec<String> = std::fs::read_dir(&dir)
            .unwrap()
            .filter_map(|e| e.ok()?.file_name().into_string().ok())
            .filter_map(|n| n.strip_suffix(".glb").map(str::to_owned))
            .collect();
        names.sort();
        for n in names {
            let mesh =
                read_mesh(&std::fs::read(dir.join(format!("{n}.glb"))).unwrap(), &GltfReadOptions::default()).unwrap();
            let lm =
                parse_landmarks(&std::fs::read_to_string(dir.join(format!("{n}.landmarks.json"))).unwrap()).unwrap();
            out.push((format!("{sub}/{n}"), mesh, lm));
        }
    }
    assert!(out.len() >= 20, "expected 8 bodies and 12 sizes, found {}", out.len());
    out
}
