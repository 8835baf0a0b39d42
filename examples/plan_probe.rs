//! Development probe (issue #14): grade a built-in template on the ASTM
//! chart's 12 fixture bodies as one run — the base size first, its dart
//! plan carried to the other sizes — and print every piece's p95 edge
//! strain, |E_s| and darts per size.
//!
//! `cargo run --release --example plan_probe -- trousers [base]`
//! (`AUTO='{"max_darts":2}'` overrides the base size's dart search,
//! `EACH=1` searches every size afresh instead, for comparison).

use std::path::Path;

use grade3d::body::derive::{derive_features, DeriveOptions};
use grade3d::collide::cache::Obstacle;
use grade3d::collide::render::{GpuContext, RenderOptions};
use grade3d::geom::winding::{WindingOptions, WindingTree};
use grade3d::io::gltf::{read_mesh, GltfReadOptions};
use grade3d::io::landmarks::parse_landmarks;
use grade3d::pipeline::{grade_with_plan, GradeOptions};
use grade3d::template::library::builtin;

const SIZES: [&str; 12] = ["00", "0", "2", "4", "6", "8", "10", "12", "14", "16", "18", "20"];

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let which = args.get(1).cloned().unwrap_or_else(|| "trousers".into());
    let base = args.get(2).cloned().unwrap_or_else(|| "10".into());
    let each = std::env::var("EACH").is_ok();
    let t = builtin().unwrap().into_iter().find(|t| t.name.contains(which.as_str())).unwrap();
    let gpu = GpuContext::new().unwrap();
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("fixtures/astm");
    let mut go = GradeOptions::default();
    if let Ok(a) = std::env::var("AUTO") {
        go.pattern.auto_darts = serde_json::from_str(&a).unwrap();
    }
    let order: Vec<&str> = std::iter::once(base.as_str()).chain(SIZES.iter().copied().filter(|s| *s != base)).collect();
    let mut plan = None;
    let (mut worst, mut worst_es, mut above4) = (0.0f64, 0.0f64, 0);
    for size in order {
        let name = format!("size-{size}");
        let mesh =
            read_mesh(&std::fs::read(dir.join(format!("{name}.glb"))).unwrap(), &GltfReadOptions::default()).unwrap();
        let lm =
            parse_landmarks(&std::fs::read_to_string(dir.join(format!("{name}.landmarks.json"))).unwrap()).unwrap();
        let body = derive_features(mesh, &lm, &DeriveOptions::default()).unwrap();
        let maps = gpu.render(&body.mesh, &RenderOptions::default()).unwrap();
        let obstacle = Obstacle { maps, tree: WindingTree::new(&body.mesh, &WindingOptions::default()) };
        let ob = if std::env::var("NOCOLLIDE").is_ok() { None } else { Some(&obstacle) };
        let g = match grade_with_plan(&t, &body, ob, size, &go, if each { None } else { plan.as_ref() }) {
            Ok(g) => g,
            Err(e) => {
                println!("{size}: ERROR {e}");
                continue;
            }
        };
        let mut line = format!("{size:>3}");
        for r in &g.pattern.reports {
            let d = &r.distortion;
            worst = worst.max(d.strain_p95);
            worst_es = worst_es.max(d.area_accuracy.abs());
            if d.strain_p95 > 0.04 {
                above4 += 1;
            }
            let darts: Vec<String> =
                r.found_darts.iter().map(|f| format!("{:.0}{:?}", f.intake_mm, f.origin)).collect();
            line += &format!(
                " {}:{:.2}%/{:.2}% flips {} [{}]",
                r.name,
                d.strain_p95 * 100.0,
                d.area_accuracy * 100.0,
                d.flipped,
                darts.join(",")
            );
        }
        if !g.pattern.darts_left_out.is_empty() {
            line += &format!(" out:{:?}", g.pattern.darts_left_out.iter().map(|d| d.0.clone()).collect::<Vec<_>>());
        }
        for pair in &g.pattern.cut_pairs {
            let ([l, r], d) = (&pair.panels, pair.difference);
            line +=
                &format!(" | {l}/{r} {:.3}% {:.2} mm", d.area_pct.max(d.width_pct).max(d.height_pct), d.sew_line_mm);
        }
        println!("{line}");
        if plan.is_none() {
            plan = Some(g.pattern.dart_plan.clone());
        }
    }
    println!("worst p95 {:.2} %, worst |E_s| {:.2} %, pieces above 4 %: {above4}", worst * 100.0, worst_es * 100.0);
}
