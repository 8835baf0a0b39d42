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
                if let Ok(dir) = std::env::var("DUMP") {
                    // OBJ of the body and the garment, and the pairs (garment triangle, body face), for plotting
                    let obj = |pos: &[DVec3], tris: &[[u32; 3]]| {
                        let mut s = String::new();
                        for p in pos {
                            s += &format!("v {} {} {}\n", p.x, p.y, p.z);
                        }
                        for t in tris {
                            s += &format!("f {} {} {}\n", t[0] + 1, t[1] + 1, t[2] + 1);
                        }
                        s
                    };
                    let bt: Vec<[u32; 3]> = body.mesh.triangles().iter().map(|t| t.map(|v| v.0)).collect();
                    std::fs::write(format!("{dir}/body.obj"), obj(body.mesh.positions(), &bt)).unwrap();
                    std::fs::write(
                        format!("{dir}/garment.obj"),
                        obj(
                            &g.mesh.positions.raw,
                            &g.mesh.triangles.iter().map(|t| t.map(|v| v.0)).collect::<Vec<_>>(),
                        ),
                    )
                    .unwrap();
                    let fixed: Vec<String> = g.mesh.fixed.iter().map(|f| u8::from(*f).to_string()).collect();
                    std::fs::write(format!("{dir}/fixed.txt"), fixed.join("\n")).unwrap();
                    let pl: Vec<String> =
                        pairs.iter().map(|p| format!("{} {}", p.garment, FaceId::idx(p.body))).collect();
                    std::fs::write(format!("{dir}/pairs.txt"), pl.join("\n")).unwrap();
                    let fp: Vec<String> = body
                        .points
                        .iter()
                        .map(|(id, q)| format!("{id} {} {} {}", q.position.x, q.position.y, q.position.z))
                        .collect();
                    std::fs::write(format!("{dir}/points.txt"), fp.join("\n")).unwrap();
                }
                if let Some(c) = &body.thigh_contact {
                    let far: Vec<String> = pairs
                        .iter()
                        .filter(|p| !c.reaches(&obstacle.tree.face_corners(p.body)))
                        .map(|p| {
                            let f = obstacle.tree.face_corners(p.body);
                            let d = f.iter().map(|&q| c.distance(q)).fold(f64::INFINITY, f64::min);
                            let gt = g.mesh.triangles[p.garment].map(|v| g.mesh.positions[v]);
                            let dg = gt.iter().map(|&q| c.distance(q)).fold(f64::INFINITY, f64::min);
                            let e = (0..3).map(|k| gt[k].distance(gt[(k + 1) % 3])).fold(0.0, f64::max);
                            format!("g{} at {:.3?}: {:.1} mm from the contact, garment triangle {:.1} mm (longest edge {:.1} mm)", p.garment, f[0], d * 1e3, dg * 1e3, e * 1e3)
                        })
                        .collect();
                    eprintln!(
                        "    thigh contact {:.1} mm below the crotch, {:.0} mm long: pairs beyond its reach {far:?}",
                        c.depth_below_crotch_mm, c.length_mm
                    );
                }
                // is each pair's body triangle part of the body's boundary, or buried inside another part of the body?
                let buried = |f: FaceId| {
                    let c = obstacle.tree.face_corners(f);
                    let n = (c[1] - c[0]).cross(c[2] - c[0]).normalize();
                    // just off the face on its outer side: 0 on the body's boundary, ≥ 1 when buried in another part
                    obstacle.tree.winding_number_exact((c[0] + c[1] + c[2]) / 3.0 + 2e-4 * n)
                };
                let ws: Vec<f64> = pairs.iter().map(|p| buried(p.body)).collect();
                let nb = ws.iter().filter(|w| **w > 0.5).count();
                let gw: Vec<f64> = pairs
                    .iter()
                    .map(|p| {
                        let t = g.mesh.triangles[p.garment].map(|v| g.mesh.positions[v]);
                        obstacle.tree.winding_number_exact((t[0] + t[1] + t[2]) / 3.0)
                    })
                    .collect();
                eprintln!(
                    "    {} pairs, {nb} with a buried body triangle (winding > 0.5 just outside its centroid); body windings {:.2?}; garment centroid windings {:.2?}",
                    pairs.len(),
                    ws.iter().take(20).collect::<Vec<_>>(),
                    gw.iter().take(20).collect::<Vec<_>>()
                );
                // the exterior gap at each pair's body triangle: from its centroid along its outward normal to the next body surface
                let gap = |f: FaceId| -> f64 {
                    let c = obstacle.tree.face_corners(f);
                    let n = (c[1] - c[0]).cross(c[2] - c[0]).normalize();
                    let o = (c[0] + c[1] + c[2]) / 3.0 + 1e-6 * n;
                    let reach = 0.05;
                    let mut best = f64::INFINITY;
                    obstacle.tree.faces_in_box(o.min(o + reach * n), o.max(o + reach * n), |h, t| {
                        if h == f {
                            return;
                        }
                        let (e1, e2) = (t[1] - t[0], t[2] - t[0]);
                        let pv = n.cross(e2);
                        let det = e1.dot(pv);
                        if det.abs() < 1e-18 {
                            return;
                        }
                        let tv = o - t[0];
                        let u = tv.dot(pv) / det;
                        let qv = tv.cross(e1);
                        let v = n.dot(qv) / det;
                        let d = e2.dot(qv) / det;
                        if u >= 0.0 && v >= 0.0 && u + v <= 1.0 && d > 0.0 && d < best {
                            best = d;
                        }
                    });
                    best * 1e3
                };
                let mut gaps: Vec<f64> = pairs.iter().map(|p| gap(p.body)).collect();
                gaps.sort_by(f64::total_cmp);
                let q = |x: f64| gaps.get(((gaps.len() as f64 - 1.0) * x) as usize).copied().unwrap_or(f64::NAN);
                eprintln!(
                    "    exterior gap at the pairs' body triangles, mm: min {:.2} p25 {:.2} median {:.2} p75 {:.2} p90 {:.2} max {:.2}; under 3 mm: {}",
                    q(0.0), q(0.25), q(0.5), q(0.75), q(0.9), q(1.0), gaps.iter().filter(|g| **g < 3.0).count()
                );
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
                    let gt = g.mesh.triangles[p.garment];
                    for v in gt {
                        let q = g.mesh.positions[v];
                        eprintln!(
                            "      v{v} {:.3?} depth {:.1} mm fixed {}",
                            q.to_array(),
                            obstacle.tree.signed_depth(q) * 1e3,
                            g.mesh.fixed[v]
                        );
                    }
                    let fixed = gt.iter().filter(|v| g.mesh.fixed[**v]).count();
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
