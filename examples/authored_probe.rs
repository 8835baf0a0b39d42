//! Development probe: author MakeHuman's helper skirt (issue #18) on its
//! design body, decide its block there, and grade it on the ASTM sizes and
//! on issue #7's population bodies, printing each piece's p95 edge strain,
//! |E_s| and darts (mouth height above the hip plane, apex height, intake).
//!
//! `cargo run --release --example authored_probe -- [filter]`
//! (the filter picks ASTM sizes by name; `FIXTURES=1` adds the fixture
//! bodies, `FIXTURES=older` those whose name contains it; each grade's
//! line ends with its mirror pairs, cut as one or apart, and their sew-line
//! and extent differences; `POP=6,15,9s` adds population bodies, `9s` body 9's scan-like copy;
//! `DECIDE=1` decides the darts on every body instead of carrying the
//! block's; `AUTO='{"enabled":false}'` overrides the found-dart search's
//! options; `NODES=1` lists how each node is placed (`DECODE=1` those that
//! decoding on the design body moves); `TEMPLATE=a-line-skirt`
//! probes that built-in template on its reference body instead; `LINES=1`
//! prints each piece's internal lines and their problems.)
//!
//! The live shift dress: `TEMPLATE=live:shift-dress` (or `live:t-shirt`) draws it with `DOPTS`
//! (JSON `ShiftDressOptions`) and authors it with `GOPTS` (JSON overriding
//! `drawn::garment_options()`), printing its drawn pieces flattened as they
//! are and, for the design body, the graded surface's signed distance from
//! the designed one by height above the hip (with `DUMP=dir`, per vertex
//! in `dir/deviation.txt`, and each flattened piece's triangle strains in
//! `dir/strain-<piece>.txt`). `SURFACE=path` writes the drawn OBJ, `FLAT_ONLY=1` stops there;
//! `REFIT=k` adds nodes where the graded surface strays most, `k` rounds.
//! Any template: `SVG=dir` writes each grade's pieces, `GRADED=dir` each
//! graded surface (OBJ), `COARSE=path` the coarse mesh on its design body (`COARSE_ALL=dir`
//! on every body; `COARSE_ONLY=1` stops there),
//! `PANELS=1` flattens every grade's panels freely (as the drawn ones;
//! with `DUMP=dir` each panel's OBJ too; `FLATTEN='{"pin_tie":0.05}'` sets
//! that flattening's options), and
//! `FAR=mm` lists each body's coarse nodes whose clearance from the body
//! differs from the design body's by more than `mm`;
//! `NOCOLL=1`, `UNGUIDED=1`, `FREE_SEAMS=1`, `LEVELS=n` turn off collision
//! on the design body, the guided dart rules, the seam negotiation, or set
//! the subdivision levels.

use grade3d::body::derive::Landmarks;
use grade3d::body::derive::{derive_features, DeriveOptions};
use grade3d::body::feature::FeatureBody;
use grade3d::body::vocab::CurveId;
use grade3d::collide::cache::Obstacle;
use grade3d::collide::render::{GpuContext, RenderOptions};
use grade3d::geom::winding::{WindingOptions, WindingTree};
use grade3d::io::gltf::read_mesh;
use grade3d::mannequin::landmarks::hm08_landmarks;
use grade3d::mannequin::model::BodyModel;
use grade3d::mannequin::population::{sample_population, scan_like};
use grade3d::pattern::garment::DartSource;
use grade3d::pipeline::{grade_with_darts, GradeOptions, Graded};
use grade3d::template::from_garment::{author_from_garment, GarmentOptions};
use grade3d::template::garment_panels::PanelMesh;
use grade3d::template::girth::girth_plane;

#[path = "../tests/common/mod.rs"]
mod common;

fn main() {
    let filter = std::env::args().nth(1);
    let gpu = GpuContext::new().unwrap();
    let obstacle = |b: &FeatureBody| Obstacle {
        maps: gpu.render(&b.mesh, &RenderOptions::default()).unwrap(),
        tree: WindingTree::new(&b.mesh, &WindingOptions::default()),
    };
    let root = common::fixtures();
    let model = BodyModel::embedded().unwrap();
    let base = model.base_mesh().unwrap();
    let lm = hm08_landmarks(model, &base, &Default::default()).unwrap();
    let mut design = derive_features(base, &lm, &DeriveOptions::default()).unwrap();
    let m = read_mesh(&std::fs::read(root.join("garments/helper-skirt.glb")).unwrap(), &Default::default())
        .unwrap()
        .welded(1e-9)
        .unwrap();
    let piece = PanelMesh {
        name: "skirt".into(),
        positions: m.positions().to_vec(),
        triangles: m.triangles().iter().map(|t| t.map(|v| v.0)).collect(),
        uv: Vec::new(),
    };
    let t = match std::env::var("TEMPLATE") {
        Ok(name) if name == "live:shift-dress" || name == "live:t-shirt" => {
            // the dress drawn here with `DOPTS` (JSON ShiftDressOptions; TShirtOptions for the T-shirt);
            // `SURFACE=path` writes its OBJ
            design = grade3d::template::library::reference_body().unwrap();
            let pieces = if name == "live:t-shirt" {
                live_pieces(&design, grade3d::template::drawn::t_shirt_surface)
            } else {
                live_pieces(&design, grade3d::template::drawn::shift_dress_surface)
            };
            if std::env::var("FLAT_ONLY").is_ok() {
                return;
            }
            let mut o = grade3d::template::drawn::garment_options();
            if let Ok(j) = std::env::var("GOPTS") {
                let mut v = serde_json::to_value(&o).unwrap();
                let over: serde_json::Value = serde_json::from_str(&j).unwrap();
                for (k, x) in over.as_object().unwrap() {
                    v[k] = x.clone();
                }
                o = serde_json::from_value(v).unwrap();
            }
            let mut a = author_from_garment("shift-dress", &pieces, &design, &o).unwrap();
            // REFIT=k: k rounds of nodes added where the refined surface strays most from the designed one
            let rounds: usize = std::env::var("REFIT").map(|r| r.parse().unwrap()).unwrap_or(0);
            for round in 0..rounds {
                use grade3d::geom::query::SphereIndex;
                let g = grade_with_darts(
                    &a.template,
                    &design,
                    None,
                    "design",
                    &GradeOptions::default(),
                    DartSource::Decide,
                )
                .unwrap();
                let si = SphereIndex::new(&a.surface);
                let mut far: Vec<(f64, glam::DVec3)> = g
                    .mesh
                    .positions
                    .iter()
                    .map(|&q| {
                        let c = si.closest_point(&a.surface, q);
                        (c.distance, c.point)
                    })
                    .collect();
                far.sort_by(|x, y| y.0.total_cmp(&x.0));
                let spacing = 0.6 * o.max_edge_mm * 1e-3;
                let tol = 2.0e-3;
                let mut existing: Vec<glam::DVec3> =
                    a.template.nodes.iter().map(|n| glam::DVec3::from_array(n.reference)).collect();
                let mut added = 0;
                for (d, p) in far {
                    if d < tol || added >= 12 {
                        break;
                    }
                    if existing.iter().all(|e| e.distance(p) > spacing) {
                        o.nodes.push(p.to_array());
                        existing.push(p);
                        added += 1;
                    }
                }
                println!("refit round {round}: {added} nodes added");
                if added == 0 {
                    break;
                }
                a = author_from_garment("shift-dress", &pieces, &design, &o).unwrap();
            }
            println!("unmapped {:?}", a.unmapped);
            let _ = SURFACE_OF.set(a.surface.clone());
            a.template
        }
        Ok(name) if name == "live:sleeves" => {
            // the short sleeves drawn here with `DOPTS` (JSON SleeveOptions)
            design = grade3d::template::library::reference_body().unwrap();
            let pieces = live_pieces(&design, grade3d::template::drawn::sleeves_surface);
            let a =
                author_from_garment("sleeves", &pieces, &design, &grade3d::template::drawn::garment_options()).unwrap();
            println!("sleeves: {} nodes, tied to {:?}", a.template.nodes.len(), {
                let mut ties: Vec<String> = a.template.nodes.iter().map(|n| n.point.to_string()).collect();
                ties.sort();
                ties.dedup();
                ties
            });
            println!("unmapped {:?}", a.unmapped);
            let _ = SURFACE_OF.set(a.surface.clone());
            a.template
        }
        Ok(name) if name.starts_with("drawn:") => {
            // a drawn style authored here: `GOPTS` (JSON) overrides the authoring options
            design = grade3d::template::library::reference_body().unwrap();
            // as tests/from_garment.rs reads it: the fixture OBJ (its vertices numbered by first use)
            let obj = root.join(format!("garments/{}.obj", &name["drawn:".len()..]));
            let pieces = grade3d::io::obj::read_obj_panels(&std::fs::read_to_string(obj).unwrap()).unwrap();
            let mut o: GarmentOptions =
                std::env::var("GOPTS").map(|j| serde_json::from_str(&j).unwrap()).unwrap_or_default();
            o.cut = grade3d::template::from_garment::TubeCut::None;
            author_from_garment(&name[6..], &pieces, &design, &o).unwrap().template
        }
        Ok(name) => {
            design = grade3d::template::library::reference_body().unwrap();
            grade3d::template::library::builtin().unwrap().into_iter().find(|t| t.name == name).unwrap()
        }
        Err(_) => author_from_garment("helper-skirt", &[piece], &design, &GarmentOptions::default()).unwrap().template,
    };
    let mut t = t;
    if std::env::var("UNGUIDED").is_ok() {
        t.defaults.guided_darts = false;
    }
    if let Ok(path) = std::env::var("COARSE") {
        // the template's coarse mesh on its design body
        let positions = t.nodes.iter().map(|n| glam::DVec3::from_array(n.reference)).collect();
        write_mesh(&path, "coarse", positions, (0..t.faces.len()).map(|f| t.face_nodes(f)).collect());
    }
    if std::env::var("DECODE").is_ok() {
        // nodes that decoding on the design body does not put back on their reference
        let m = grade3d::template::codec::decode(&t, &design, t.defaults.relocation).unwrap();
        println!("decode: relocation {:?}", t.defaults.relocation);
        // nodes without a node at their mirror image across the body's mid-sagittal plane
        let ((n, d), _) = grade3d::refine::symmetry::body_plane(&design).unwrap();
        let refs: Vec<glam::DVec3> = t.nodes.iter().map(|n| glam::DVec3::from_array(n.reference)).collect();
        for (i, &p) in refs.iter().enumerate() {
            let m = p - 2.0 * (n.dot(p) - d) * n;
            let (j, d) =
                refs.iter().enumerate().map(|(j, q)| (j, q.distance(m))).min_by(|a, b| a.1.total_cmp(&b.1)).unwrap();
            if d > 1e-4 {
                println!(
                    "decode: node {i} ({}) nearest mirror node {j} ({}) {:.2} mm",
                    t.nodes[i].point,
                    t.nodes[j].point,
                    d * 1e3
                );
            }
        }
        for (i, (n, p)) in t.nodes.iter().zip(&m.positions).enumerate() {
            let off = glam::DVec3::from_array(n.reference).distance(*p) * 1e3;
            if off > 0.1 {
                println!("decode: node {i} ({}) {off:.2} mm off its reference", n.point);
            }
        }
    }
    if std::env::var("NODES").is_ok() {
        let hip = girth_plane(&design, CurveId::Hip).unwrap();
        for (i, n) in t.nodes.iter().enumerate() {
            let i = i as u32;
            let kind = if t.below.iter().any(|b| b.node == i) {
                "below"
            } else if t.between.iter().any(|b| b.node == i) {
                "between"
            } else if t.on_curve.iter().any(|b| b.node == i) {
                "on_curve"
            } else {
                "eq1"
            };
            let p = glam::DVec3::from_array(n.reference);
            println!(
                "node {i:3} {kind:8} {:24} {:+5.0} mm above hip, x {:+4.0} z {:+4.0}",
                n.point.to_string(),
                hip.signed_distance(p) * 1e3,
                p.x * 1e3,
                p.z * 1e3
            );
        }
    }
    if std::env::var("COARSE_ONLY").is_ok() {
        return;
    }
    let mut go = GradeOptions::default();
    if let Ok(l) = std::env::var("LEVELS") {
        go.levels = Some(l.parse().unwrap());
    }
    if std::env::var("FREE_SEAMS").is_ok() {
        go.pattern.negotiate_seams = false;
    }
    if let Ok(f) = std::env::var("PFLAT") {
        go.pattern.flatten = serde_json::from_str(&f).unwrap();
    }
    if let Ok(a) = std::env::var("AUTO") {
        go.pattern.auto_darts = serde_json::from_str(&a).unwrap();
    }
    let design_obstacle = obstacle(&design);
    // the graded surface cut into its panels, each flattened freely (as the drawn pieces are)
    let panels_flat = |g: &Graded| {
        let (panels, _) = grade3d::pattern::panels::cut(&t, &g.cut_positions, &g.mesh.triangles, &g.lineage).unwrap();
        let pieces: Vec<PanelMesh> = panels
            .iter()
            .map(|p| PanelMesh {
                name: format!("graded-{}", p.name),
                positions: p.positions.iter().copied().collect(),
                triangles: p.triangles.iter().map(|t| t.map(|v| usize::from(v) as u32)).collect(),
                uv: Vec::new(),
            })
            .collect();
        flat_report(&pieces);
    };
    let panels_too = std::env::var("PANELS").is_ok();
    if panels_too {
        panels_flat(&grade_with_darts(&t, &design, None, "design", &go, DartSource::Decide).unwrap());
    }
    let g = grade_with_darts(
        &t,
        &design,
        if std::env::var("NOCOLL").is_ok() { None } else { Some(&design_obstacle) },
        "design",
        &go,
        DartSource::Decide,
    )
    .unwrap();
    let plan = g.pattern.dart_plan.clone();
    print(&design, "design", &g);
    let decide = std::env::var("DECIDE").is_ok();
    let mut bodies: Vec<(String, FeatureBody)> = Vec::new();
    // the ASTM sizes matching the filter, and with `FIXTURES=1` the eight fixture bodies
    // (`FIXTURES=older`: those whose name contains it)
    let fixtures = std::env::var("FIXTURES").ok();
    for (name, mesh, lm) in common::fixture_bodies() {
        let astm = name.starts_with("astm/") && filter.as_ref().is_none_or(|f| name.contains(f.as_str()));
        let fixture =
            name.starts_with("bodies/") && fixtures.as_ref().is_some_and(|f| f == "1" || name.contains(f.as_str()));
        if astm || fixture {
            bodies.push((name, derive_features(mesh, &lm, &DeriveOptions::default()).unwrap()));
        }
    }
    if let Ok(pop) = std::env::var("POP") {
        let people = sample_population(40, 13);
        for item in pop.split(',') {
            // `9s`: the scan-like copy of body 9 (tests/population.rs)
            let scan = item.ends_with('s');
            let i: usize = item.trim_end_matches('s').parse().unwrap();
            let p = &people[i];
            let mesh = model.build(&p.params).unwrap();
            let lm = hm08_landmarks(model, &mesh, &Default::default()).unwrap();
            if scan {
                let s = scan_like(&mesh, 60_000, 1e-3, 13 ^ i as u64).unwrap();
                let lm = Landmarks { points: lm.points.clone(), curves: Default::default() };
                bodies.push((format!("{}-scan", p.name), derive_features(s, &lm, &DeriveOptions::default()).unwrap()));
            } else {
                bodies.push((p.name.clone(), derive_features(mesh, &lm, &DeriveOptions::default()).unwrap()));
            }
        }
    }
    // `FAR=mm`: each body's coarse nodes whose clearance from the body differs from the design body's by more
    let far: Option<f64> = std::env::var("FAR").ok().map(|f| f.parse().unwrap());
    let clearance = |b: &FeatureBody| -> Vec<f64> {
        let index = grade3d::geom::query::SphereIndex::new(&b.mesh);
        let m = grade3d::template::codec::decode(&t, b, grade3d::template::format::Relocation::Eq1Frame).unwrap();
        m.positions.iter().map(|&p| index.closest_point(&b.mesh, p).point.distance(p) * 1e3).collect()
    };
    let design_clearance = far.map(|_| clearance(&design));
    for (name, body) in &bodies {
        if let (Some(limit), Some(before)) = (far, &design_clearance) {
            for (i, (now, then)) in clearance(body).iter().zip(before).enumerate() {
                if (now - then).abs() > limit {
                    let n = &t.nodes[i];
                    let kind = if t.below.iter().any(|b| b.node == i as u32) {
                        "below"
                    } else if t.between.iter().any(|b| b.node == i as u32) {
                        "between"
                    } else {
                        "eq1"
                    };
                    println!(
                        "  {name}: node {i} ({kind}, {}) clearance {then:.0} → {now:.0} mm, at {:?}",
                        n.point, n.reference
                    );
                }
            }
        }
        if let Ok(dir) = std::env::var("COARSE_ALL") {
            // the coarse mesh decoded on every body
            let m =
                grade3d::template::codec::decode(&t, body, grade3d::template::format::Relocation::Eq1Frame).unwrap();
            let path = format!("{dir}/{}-coarse.obj", name.replace('/', "-"));
            write_mesh(&path, "coarse", m.positions.clone(), (0..t.faces.len()).map(|f| t.face_nodes(f)).collect());
        }
        let o = obstacle(body);
        let src = if decide { DartSource::Decide } else { DartSource::Block(&plan) };
        let start = std::time::Instant::now();
        match grade_with_darts(&t, body, Some(&o), name, &go, src) {
            Ok(g) => {
                if panels_too {
                    panels_flat(&g);
                }
                print(body, name, &g);
                println!("    {:.1} s", start.elapsed().as_secs_f64());
            }
            Err(e) => println!("{name}: ERROR {e}"),
        }
    }
}

static SURFACE_OF: std::sync::OnceLock<grade3d::geom::mesh::TriMesh> = std::sync::OnceLock::new();

fn print(body: &FeatureBody, name: &str, g: &Graded) {
    for r in g.pattern.reports.iter().filter(|r| !r.converged) {
        println!("    piece {} not converged after {} iterations", r.name, r.iterations);
    }
    for s in g.pattern.seams.iter().filter(|s| s.mismatch_mm > 1.0) {
        println!(
            "    seam {} ({} / {}) mismatch {:.2} mm: {:.1} vs {:.1} mm, 3D {:.1} mm",
            s.name, s.piece_a, s.piece_b, s.mismatch_mm, s.length_a_mm, s.length_b_mm, s.length_3d_mm
        );
    }
    if let (Some(surface), "design") = (SURFACE_OF.get(), name) {
        // graded → designed, signed outwards (from the body's vertical axis), by height above the hip
        use grade3d::geom::query::SphereIndex;
        let hip = girth_plane(body, CurveId::Hip).unwrap();
        let si = SphereIndex::new(surface);
        let ring = &body.curves[&CurveId::Hip].polyline.points;
        let centre = ring.iter().copied().sum::<glam::DVec3>() / ring.len() as f64;
        let graded = g.cut_mesh().unwrap();
        let mut bands: std::collections::BTreeMap<i64, Vec<f64>> = Default::default();
        let mut far: std::collections::BTreeMap<(i64, i64), usize> = Default::default();
        let mut dump = String::new();
        for &q in graded.positions() {
            let c = si.closest_point(surface, q);
            let h = hip.signed_distance(q);
            let axis = centre + hip.normal * (h - hip.signed_distance(centre));
            let out = (c.point - axis - hip.normal * (c.point - axis).dot(hip.normal)).normalize_or_zero();
            let dist = (q - c.point).dot(out) * 1e3;
            dump += &format!("{} {} {} {dist}\n", q.x, q.y, q.z);
            bands.entry((h * 1e3 / 40.0).floor() as i64).or_default().push(dist);
            if dist.abs() > 4.0 {
                // angle round the body: 0 its left, 90 its front
                let ang = out.z.atan2(out.x).to_degrees();
                *far.entry(((h * 1e3 / 40.0).floor() as i64 * 40, (ang / 30.0).round() as i64 * 30)).or_insert(0) += 1;
            }
        }
        for (b, v) in &bands {
            let mean = v.iter().sum::<f64>() / v.len() as f64;
            let mut a: Vec<f64> = v.iter().map(|x| x.abs()).collect();
            a.sort_by(f64::total_cmp);
            println!(
                "  band {:+5} mm: n {:5} signed mean {:+6.2} |p95| {:5.2}",
                b * 40,
                v.len(),
                mean,
                a[a.len() * 95 / 100]
            );
        }
        println!("  over 4 mm (height, angle): {far:?}");
        if let Ok(dir) = std::env::var("DUMP") {
            std::fs::write(format!("{dir}/deviation.txt"), dump).unwrap();
        }
    }
    if let Ok(dir) = std::env::var("GRADED") {
        // the graded surface, one OBJ a body
        let triangles = g.mesh.triangles.iter().map(|t| t.map(|v| usize::from(v) as u32)).collect();
        let path = format!("{dir}/{}-graded.obj", name.replace('/', "-"));
        write_mesh(&path, "graded", g.mesh.positions.iter().copied().collect(), triangles);
        // and the surface the pattern is cut from (symmetrised on a symmetric body)
        let triangles = g.mesh.triangles.iter().map(|t| t.map(|v| usize::from(v) as u32)).collect();
        let path = format!("{dir}/{}-cut.obj", name.replace('/', "-"));
        write_mesh(&path, "cut", g.cut_positions.iter().copied().collect(), triangles);
    }
    if let Ok(dir) = std::env::var("SVG") {
        let svg = grade3d::pattern::export::svg::pieces_svg(&g.pattern.pieces, &Default::default());
        std::fs::write(format!("{dir}/{}.svg", name.replace('/', "-")), svg).unwrap();
    }
    let hip = girth_plane(body, CurveId::Hip).unwrap();
    let mut line = format!("{name:28}");
    for r in &g.pattern.reports {
        let d = &r.distortion;
        line += &format!(" {}:{:.2}%/{:+.2}%", r.name, d.strain_p95 * 100.0, d.area_accuracy * 100.0);
        if let Some(h) = &r.hotspot {
            line += &format!("[{} {:.0}mm]", h.near, h.distance_mm);
        }
        if r.sew_line_self_intersects {
            line += "(X)";
        }
    }
    if g.collision.surface.pairs_after > 0 {
        let s = &g.collision.surface;
        line += &format!(" THROUGH:{} ({} at the thigh contact)", s.pairs_after, s.pairs_after_at_thigh_contact);
    }
    for pair in &g.pattern.cut_pairs {
        let d = &pair.difference;
        line += &format!(
            " [{}{} {:.2}mm {:.2}%]",
            pair.piece,
            if pair.cut_as_pair { " pair" } else { " apart" },
            d.sew_line_mm,
            d.area_pct.max(d.width_pct).max(d.height_pct)
        );
    }
    println!("{line}");
    for p in &g.pattern.pieces {
        let widths: Vec<String> = p
            .internal_lines
            .iter()
            .filter(|l| l.name.contains("dart"))
            .map(|l| format!("{:.1}", l.points[0].distance(l.points[l.points.len() - 1])))
            .collect();
        println!("    {} dart openings (mm): {}", p.name, widths.join(" "));
    }
    if std::env::var("LINES").is_ok() {
        for p in &g.pattern.pieces {
            for l in &p.internal_lines {
                let (a, b) = (l.points[0], l.points[l.points.len() - 1]);
                println!(
                    "    {} {}: {} points, ({:.0},{:.0}) → ({:.0},{:.0})",
                    p.name,
                    l.name,
                    l.points.len(),
                    a.x,
                    a.y,
                    b.x,
                    b.y
                );
            }
            for e in grade3d::pattern::lines::line_problems(p) {
                println!("    {} PROBLEM {e:?}", p.name);
            }
        }
    }
    for d in &g.pattern.dart_plan.found {
        let (Some(&m), Some(&a)) = (d.chain.first(), d.chain.last()) else { continue };
        let (pm, pa) = (g.cut_positions[m], g.cut_positions[a]);
        let fd = g.pattern.reports.iter().flat_map(|r| &r.found_darts).find(|f| f.name == d.name);
        println!(
            "    {} mouth {:+.0} mm apex {:+.0} mm above hip, mouth x {:+.0} mm, intake {:.1} mm",
            d.name,
            hip.signed_distance(pm) * 1e3,
            hip.signed_distance(pa) * 1e3,
            pm.x * 1e3,
            fd.map_or(f64::NAN, |f| f.intake_mm)
        );
    }
}

/// Each drawn piece flattened as it is (no template, no grade): its p95 edge strain.
fn flat_report(pieces: &[PanelMesh]) {
    use grade3d::pattern::flatten::{distortion, flatten, FlattenOptions};
    use grade3d::pattern::panels::{PanelFace, PanelVertex};
    use typed_index_collections::TiVec;
    let mut line = "drawn surface flattened:".to_string();
    for p in pieces {
        let pos: TiVec<PanelVertex, glam::DVec3> = p.positions.iter().copied().collect();
        let tri: TiVec<PanelFace, [PanelVertex; 3]> =
            p.triangles.iter().map(|t| t.map(|i| PanelVertex::from(i as usize))).collect();
        // `FLATTEN='{"pin_tie":0.1}'`: the flattening's options
        let fo: FlattenOptions =
            std::env::var("FLATTEN").map(|j| serde_json::from_str(&j).unwrap()).unwrap_or_default();
        let f = match flatten(&pos, &tri, &fo) {
            Ok(f) => f,
            Err(e) => {
                if let grade3d::pattern::flatten::FlattenError::DegenerateTriangle { face } = e {
                    println!("  {}: degenerate triangle {face}: {:?}", p.name, tri[face].map(|v| pos[v]));
                }
                line += &format!(" {}:{e}", p.name);
                continue;
            }
        };
        let d = distortion(&pos, &tri, &f.uv);
        // per triangle: its 3D centroid, its flat centroid, and its worst edge strain
        let mut dump = String::new();
        for t in &tri {
            let [a, b, c] = t.map(|v| (pos[v], f.uv[v]));
            let worst = [(a, b), (b, c), (c, a)]
                .iter()
                .map(|(x, y)| (y.1.distance(x.1) / y.0.distance(x.0) - 1.0).abs())
                .fold(0.0, f64::max);
            let (c3, c2) = ((a.0 + b.0 + c.0) / 3.0, (a.1 + b.1 + c.1) / 3.0);
            dump += &format!("{} {} {} {} {} {}\n", c3.x, c3.y, c3.z, c2.x, c2.y, worst);
        }
        if let Ok(dir) = std::env::var("DUMP") {
            std::fs::write(format!("{dir}/strain-{}.txt", p.name), dump).unwrap();
            write_mesh(&format!("{dir}/{}.obj", p.name), &p.name, p.positions.clone(), p.triangles.clone());
        }
        line += &format!(" {}:{:.2}%({} flipped)", p.name, d.strain_p95 * 100.0, f.flipped);
    }
    println!("{line}");
}

/// A style drawn live on `body` with `DOPTS` (JSON options of `draw`), its
/// OBJ written to `SURFACE` where given, and its pieces flattened as they are.
fn live_pieces<O: serde::de::DeserializeOwned + Default, E: std::fmt::Debug>(
    body: &FeatureBody,
    draw: fn(&FeatureBody, &O) -> Result<Vec<PanelMesh>, E>,
) -> Vec<PanelMesh> {
    let o: O = std::env::var("DOPTS").map(|j| serde_json::from_str(&j).unwrap()).unwrap_or_default();
    let pieces = draw(body, &o).unwrap();
    if let Ok(path) = std::env::var("SURFACE") {
        std::fs::write(path, grade3d::io::obj::write_obj_panels(&pieces, "live drawing")).unwrap();
    }
    flat_report(&pieces);
    pieces
}

/// One mesh written as an OBJ of one group (`write_obj_panels`).
fn write_mesh(path: &str, name: &str, positions: Vec<glam::DVec3>, triangles: Vec<[u32; 3]>) {
    let piece = PanelMesh { name: name.into(), positions, triangles, uv: Vec::new() };
    std::fs::write(path, grade3d::io::obj::write_obj_panels(&[piece], name)).unwrap();
}
