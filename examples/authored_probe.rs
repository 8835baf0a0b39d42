//! Development probe: author MakeHuman's helper skirt (issue #18) on its
//! design body, decide its block there, and grade it on the ASTM sizes and
//! on issue #7's population bodies, printing each piece's p95 edge strain,
//! |E_s| and darts (mouth height above the hip plane, apex height, intake).
//!
//! `cargo run --release --example authored_probe -- [filter]`
//! (`POP=6,15,9s` adds population bodies, `9s` body 9's scan-like copy;
//! `DECIDE=1` decides the darts on every body instead of carrying the
//! block's; `AUTO='{"enabled":false}'` overrides the found-dart search's
//! options; `NODES=1` lists how each node is placed; `TEMPLATE=a-line-skirt`
//! probes that built-in template on its reference body instead; `LINES=1`
//! prints each piece's internal lines and their problems.)

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
        Ok(name) if name == "live:shift-dress" => {
            // the dress drawn here with `DOPTS` (JSON ShiftDressOptions); `SURFACE=path` writes its OBJ
            design = grade3d::template::library::reference_body().unwrap();
            let d: grade3d::template::drawn::ShiftDressOptions =
                std::env::var("DOPTS").map(|j| serde_json::from_str(&j).unwrap()).unwrap_or_default();
            let pieces = grade3d::template::drawn::shift_dress_surface(&design, &d).unwrap();
            if let Ok(path) = std::env::var("SURFACE") {
                std::fs::write(path, grade3d::io::obj::write_obj_panels(&pieces, "live dress")).unwrap();
            }
            author_from_garment("shift-dress", &pieces, &design, &grade3d::template::drawn::garment_options())
                .unwrap()
                .template
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
    if std::env::var("NODES").is_ok() {
        let hip = girth_plane(&design, CurveId::Hip).unwrap();
        for (i, n) in t.nodes.iter().enumerate() {
            let i = i as u32;
            let kind = if t.below.iter().any(|b| b.node == i) {
                "below"
            } else if t.between.iter().any(|b| b.node == i) {
                "between"
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
    let mut go = GradeOptions::default();
    if let Ok(a) = std::env::var("AUTO") {
        go.pattern.auto_darts = serde_json::from_str(&a).unwrap();
    }
    let design_obstacle = obstacle(&design);
    let g = grade_with_darts(&t, &design, Some(&design_obstacle), "design", &go, DartSource::Decide).unwrap();
    let plan = g.pattern.dart_plan.clone();
    print(&design, "design", &g);
    let decide = std::env::var("DECIDE").is_ok();
    let mut bodies: Vec<(String, FeatureBody)> = Vec::new();
    // the ASTM sizes matching the filter, and with `FIXTURES` the eight fixture bodies
    let fixtures = std::env::var("FIXTURES").is_ok();
    for (name, mesh, lm) in common::fixture_bodies() {
        let astm = name.starts_with("astm/") && filter.as_ref().is_none_or(|f| name.contains(f.as_str()));
        if astm || (fixtures && name.starts_with("bodies/")) {
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
    for (name, body) in &bodies {
        let o = obstacle(body);
        let src = if decide { DartSource::Decide } else { DartSource::Block(&plan) };
        let start = std::time::Instant::now();
        match grade_with_darts(&t, body, Some(&o), name, &go, src) {
            Ok(g) => {
                print(body, name, &g);
                println!("    {:.1} s", start.elapsed().as_secs_f64());
            }
            Err(e) => println!("{name}: ERROR {e}"),
        }
    }
}

fn print(body: &FeatureBody, name: &str, g: &Graded) {
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
        line += &format!(" THROUGH:{}", g.collision.surface.pairs_after);
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
