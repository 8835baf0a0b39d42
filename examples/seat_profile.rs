//! Development probe (issue #14, trouser back strain): the back profile of
//! the trousers as cut and of the body in the sagittal plane through the
//! left thigh's centre — does the cloth follow the gluteal fold?
//!
//! `cargo run --release --example seat_profile -- male-heavy-short-african`

use std::path::Path;

use grade3d::body::derive::{derive_features, DeriveOptions};
use grade3d::body::vocab::{CurveId, PointId};
use grade3d::collide::cache::Obstacle;
use grade3d::collide::render::{GpuContext, RenderOptions};
use grade3d::geom::mesh::TriMesh;
use grade3d::geom::plane::Plane;
use grade3d::geom::slice::slice;
use grade3d::geom::winding::{WindingOptions, WindingTree};
use grade3d::io::gltf::{read_mesh, GltfReadOptions};
use grade3d::io::landmarks::parse_landmarks;
use grade3d::pipeline::{grade, GradeOptions};
use grade3d::template::library::builtin;

fn main() {
    let name = std::env::args().nth(1).unwrap_or_else(|| "male-heavy-short-african".into());
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("fixtures/bodies");
    let mesh =
        read_mesh(&std::fs::read(root.join(format!("{name}.glb"))).unwrap(), &GltfReadOptions::default()).unwrap();
    let lm = parse_landmarks(&std::fs::read_to_string(root.join(format!("{name}.landmarks.json"))).unwrap()).unwrap();
    let body = derive_features(mesh, &lm, &DeriveOptions::default()).unwrap();
    let gpu = GpuContext::new().unwrap();
    let maps = gpu.render(&body.mesh, &RenderOptions::default()).unwrap();
    let obstacle = Obstacle { maps, tree: WindingTree::new(&body.mesh, &WindingOptions::default()) };
    let t = builtin().unwrap().into_iter().find(|t| t.name == "trousers").unwrap();
    let g = grade(&t, &body, Some(&obstacle), &name, &GradeOptions::default()).unwrap();
    let garment = g.cut_mesh().unwrap();
    let x = body.curves[&CurveId::ThighLeft].polyline.length_centroid().x;
    let plane = Plane { normal: glam::DVec3::X, offset: x };
    let crotch = body.points[&PointId::Crotch].position.y;
    println!("sagittal plane x = {:.1} mm; crotch y = {:.1} mm", x * 1e3, crotch * 1e3);
    let back = |m: &TriMesh, y: f64| -> Option<f64> {
        let mut best: Option<f64> = None;
        for s in slice(m, &plane) {
            let p = &s.polyline.points;
            let n = p.len();
            let segs = if s.polyline.closed { n } else { n.saturating_sub(1) };
            for i in 0..segs {
                let (a, b) = (p[i], p[(i + 1) % n]);
                if (a.y - y) * (b.y - y) <= 0.0 && a.y != b.y {
                    let z = a.z + (b.z - a.z) * (y - a.y) / (b.y - a.y);
                    best = Some(best.map_or(z, |q: f64| q.min(z)));
                }
            }
        }
        best
    };
    println!("   y-crotch(mm)   body back z   garment back z   gap");
    for k in -20..=20 {
        let y = crotch + k as f64 * 0.01;
        if let (Some(bz), Some(gz)) = (back(&body.mesh, y), back(&garment, y)) {
            println!("{:>12.0} {:>14.1} {:>16.1} {:>6.1}", k as f64 * 10.0, bz * 1e3, gz * 1e3, (bz - gz) * 1e3);
        }
    }
}
