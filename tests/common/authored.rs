//! The authored templates' inputs shared by `tests/from_garment.rs` and
//! `tests/population.rs` (issue #18: templates authored from MakeHuman's
//! helper garments, `fixtures/garments/`, on their design body).

use std::path::Path;
use std::sync::OnceLock;

use grade3d::body::derive::{derive_features, DeriveOptions};
use grade3d::body::feature::FeatureBody;
use grade3d::io::gltf::read_mesh;
use grade3d::mannequin::landmarks::hm08_landmarks;
use grade3d::mannequin::model::BodyModel;
use grade3d::template::garment_panels::PanelMesh;

/// The authored skirt's strain ceiling on the fixtures and issue #7's
/// population (p95 edge strain; `tests/from_garment.rs`'s module docs): its
/// worst are female-slim-short-asian's back, 4.38 %, and pop00-f-slim-short's
/// back, 4.56 % (3.90 % and 4.43 % while a self-mirrored piece could take two
/// mirrored pairs: issue #14 caps found darts at two a piece, a pair now
/// counting two; 10.62 % before every node below the hip hung from it). A
/// guard against regressions, not the bar.
pub const SKIRT_STRAIN_CEILING: f64 = 0.046;

/// The library's A-line skirt's strain ceiling on issue #7's population and
/// the scans (p95 edge strain): its 20 fixture and ASTM grades meet the 4 %
/// bar (3.59 % at worst, `tests/pattern.rs`); the population's reach 5.32 %
/// (pop04-f-heavy-medium's back; pop09-m-slim-short's 4.23 %, pop24's 4.35 %).
/// A guard against regressions, not the bar.
pub const A_LINE_STRAIN_CEILING: f64 = 0.055;

/// MakeHuman's base mesh with its features: the helpers' design body.
pub fn design_body() -> &'static FeatureBody {
    static B: OnceLock<FeatureBody> = OnceLock::new();
    B.get_or_init(|| {
        let model = BodyModel::embedded().unwrap();
        let base = model.base_mesh().unwrap();
        let lm = hm08_landmarks(model, &base, &Default::default()).unwrap();
        derive_features(base, &lm, &DeriveOptions::default()).unwrap()
    })
}

/// A fixture garment as one piece (MakeHuman's helpers are single meshes).
pub fn garment(name: &str) -> PanelMesh {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join(format!("fixtures/garments/{name}.glb"));
    let m = read_mesh(&std::fs::read(path).unwrap(), &Default::default()).unwrap().welded(1e-9).unwrap();
    PanelMesh {
        name: name.trim_start_matches("helper-").to_owned(),
        positions: m.positions().to_vec(),
        triangles: m.triangles().iter().map(|t| t.map(|v| v.0)).collect(),
        uv: Vec::new(),
    }
}
