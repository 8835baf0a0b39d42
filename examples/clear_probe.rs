//! Development probe (issue #13): grade the built-in templates on fixture
//! bodies and print what the surface clearing leaves: the intersecting
//! garment/body triangle pairs by height and side, the feature point nearest
//! each, and whether the body mesh crosses itself there.
//!
//! `cargo run --release --example clear_probe -- [template] [body substring | popNN | popNN-scan]`
//! (`CLEAR='{"max_rounds":24}'` overrides the surface clearing's options)

use std::path::Path;

use glam::DVec3;
use grade3d::body::derive::{derive_features, DeriveOptions};
use grade3d::collide::cache::Obstacle;
use grade3d::collide::render::{GpuContext, RenderOptions};
use grade3d::geom::intersect::{intersecting_pairs, self_intersections};
use grade3d::geom::mesh::FaceId;
use grade3d::geom::winding::{WindingOptions, WindingTree};
use grade3d::io::gltf::{read_mesh, GltfReadOptions};
use grade3d::io::landmarks::parse_landmarks;
use grade3d::pipeline::{grade, GradeOptions};
use grade3d::template::library::builtin;

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let which = args.get(1).cloned().unwrap_or_default();
    let only = args.get(2).cloned().unwrap_or_default();
    let gpu = GpuContext::new().unwrap();
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("fixtures");
    let library = builtin().unwrap();
    let mut jobs: Vec<(String, grade3d::geom::mesh::TriMesh, grade3d::body::derive::Landmarks)> = Vec::new();
    let scan = only.ends_with("-scan");
    if let Some(i) = only.strip_prefix("pop").and_then(|n| n.trim_end_matches("-scan").parse::<usize>().ok()) {
        // a body of issue #13's population (tests/population.rs: seed 13), "popNN-scan" its scan-like copy
        let model = grade3d::mannequin::model::BodyModel::embedded().unwrap();
        let b = &grade3d::mannequin::population::sample_population(40, 13)[i];
        let mesh = model.build(&b.params).unwrap();
        let mut lm = grade3d::mannequin::landmarks::hm08_landmarks(model, &mesh, &Default::default()).unwrap();
        if scan {
            let copy = grade3d::mannequin::population::scan_like(&mesh, 60_000, 1e-3, 13 ^ i as u64).unwrap();
            lm.curves.clear();
            jobs.push((format!("{}-scan", b.name), copy, lm));
        } else {
            jobs.push((b.name.clone(), mesh, lm));
        }
    }
    for sub in ["bodies", "astm"] {
        if !jobs.is_empty() {
            break;
        }
        let mut names: Vec<String> = std::fs::read_dir(root.join(sub))
            .unwrap()
            .filter_map(|e| e.ok()?.file_name().into_string().ok())
            .filter_map(|n| n.strip_suffix(".glb").map(str::to_owned))
            .collect();
        names.sort();
        for name in names.into_iter().filter(|n| n.contains(only.as_str())) {
            let dir = root.join(sub);
            let mesh = read_mesh(&std::fs::read(dir.join(format!("{name}.glb"))).unwrap(), &GltfReadOptions::default())
                .unwrap();
            let lm =
                parse_landmarks(&std::fs::read_to_string(dir.join(format!("{name}.landmarks.json"))).unwrap()).unwrap();
            jobs.push((format!("{sub}/{name}"), mesh, lm));
        }
    }
    {
        for (name, mesh, lm) in jobs {
            let sub = "";
            let body = derive_features(mesh, &lm, &DeriveOptions::default()).unwrap();
            let tree = WindingTree::new(&body.mesh, &WindingOptions::default());
            // where the body's own surface crosses itself
            let selfx: Vec<DVec3> = self_intersections(&tree, &body.mesh)
                .iter()
                .map(|(f, _)| {
                    let c = tree.face_corners(*f);
                    (c[0] + c[1] + c[2]) / 3.0
                })
                .collect();
            eprintln!("{sub}/{name}: body self-intersections {}", selfx.len());
            let maps = gpu.render(&body.mesh, &RenderOptions::default()).unwrap();
            let obstacle = Obstacle { maps, tree };
            for t in library.iter().filter(|t| t.name.contains(which.as_str())) {
                let mut go = GradeOptions::default();
                if let Ok(c) = std::env::var("CLEAR") {
                    go.clear = serde_json::from_str(&c).unwrap();
                }
                let g = grade(t, &body, Some(&obstacle), &name, &go).unwrap();
                let s = g.collision.surface;
                eprintln!("  {}: {s:?} clear {:.0} ms coarse {:?}", t.name, g.timings.clear_ms, g.collision.coarse);
                let pairs = intersecting_pairs(&obstacle.tree, &g.mesh.positions, &g.mesh.triangles);
                for p in pairs.iter().step_by((pairs.len() / 12).max(1)) {
                    let c = obstacle.tree.face_corners(p.body);
                    let m: DVec3 = (c[0] + c[1] + c[2]) / 3.0;
                    let near = body
                        .points
                        .iter()
                        .min_by(|a, b| a.1.position.distance(m).total_cmp(&b.1.position.distance(m)))
                        .map(|(id, q)| format!("{id} {:.0} mm", q.position.distance(m) * 1e3))
                        .unwrap();
                    let nearest_self = selfx.iter().map(|q| q.distance(m)).fold(f64::INFINITY, f64::min);
                    let gt = g.mesh.triangles[p.garment as usize];
                    for v in gt {
                        let q = g.mesh.positions[v as usize];
                        eprintln!(
                            "      v{v} {:.3?} depth {:.1} mm fixed {}",
                            q.to_array(),
                            obstacle.tree.signed_depth(q) * 1e3,
                            g.mesh.fixed[v as usize]
                        );
                    }
                    let fixed = gt.iter().filter(|v| g.mesh.fixed[**v as usize]).count();
                    eprintln!(
                        "    pair g{} b{}: at {:.3?} near {near}; body self-crossing {:.0} mm away; {fixed} fixed corners",
                        p.garment,
                        FaceId::idx(p.body),
                        m.to_array(),
                        nearest_self * 1e3
                    );
                }
            }
        }
    }
}
