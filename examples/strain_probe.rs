//! Development probe: grade the built-in skirt or trousers (authored in
//! memory, options from the command line as JSON) on every fixture body and
//! print each piece's p95 edge strain, |E_s| and strain hotspot.
//!
//! `cargo run --release --example strain_probe -- trousers '{"thigh_ease_mm":90}'`
//! (`AUTO='{"candidates":8}'` overrides the found-dart search's options,
//! `FLAT='{"hem_weight":0.5}'` the flattening's, `CLEAR='{"max_rounds":0}'` the
//! surface clearing's;
//! `[n]` after a piece is how many darts the search added; `FABRIC=1` adds each
//! piece's thread strain, warp and weft p95, and the weave's shear p95).

use std::path::Path;

use grade3d::body::derive::{derive_features, DeriveOptions};
use grade3d::collide::cache::Obstacle;
use grade3d::collide::render::{GpuContext, RenderOptions};
use grade3d::geom::winding::{WindingOptions, WindingTree};
use grade3d::io::gltf::{read_mesh, GltfReadOptions};
use grade3d::io::landmarks::parse_landmarks;
use grade3d::pipeline::{grade, GradeOptions};
use grade3d::template::library::{reference_body, straight_skirt, trousers};

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let which = args.get(1).map(String::as_str).unwrap_or("trousers");
    let opts = args.get(2).map(String::as_str).unwrap_or("{}");
    let only = args.get(3).cloned();
    let reference = reference_body().unwrap();
    let t = match which {
        "skirt" => straight_skirt(&reference, &serde_json::from_str(opts).unwrap()).unwrap(),
        _ => trousers(&reference, &serde_json::from_str(opts).unwrap()).unwrap(),
    };
    let gpu = GpuContext::new().unwrap();
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("fixtures");
    let (mut above, mut n, mut worst) = (0, 0, 0.0f64);
    let mut sum = 0.0;
    for sub in ["bodies", "astm"] {
        let mut names: Vec<String> = std::fs::read_dir(root.join(sub))
            .unwrap()
            .filter_map(|e| e.ok()?.file_name().into_string().ok())
            .filter_map(|n| n.strip_suffix(".glb").map(str::to_owned))
            .collect();
        names.sort();
        for name in names {
            if only.as_ref().is_some_and(|o| !name.contains(o.as_str())) {
                continue;
            }
            let dir = root.join(sub);
            let mesh = read_mesh(&std::fs::read(dir.join(format!("{name}.glb"))).unwrap(), &GltfReadOptions::default())
                .unwrap();
            let lm =
                parse_landmarks(&std::fs::read_to_string(dir.join(format!("{name}.landmarks.json"))).unwrap()).unwrap();
            let body = derive_features(mesh, &lm, &DeriveOptions::default()).unwrap();
            let maps = gpu.render(&body.mesh, &RenderOptions::default()).unwrap();
            let obstacle = Obstacle { maps, tree: WindingTree::new(&body.mesh, &WindingOptions::default()) };
            let mut go = GradeOptions::default();
            if let Ok(f) = std::env::var("FLAT") {
                go.pattern.flatten = serde_json::from_str(&f).unwrap();
            }
            if let Ok(c) = std::env::var("CLEAR") {
                go.clear = serde_json::from_str(&c).unwrap();
            }
            if let Ok(k) = std::env::var("NEGOTIATION_POWER") {
                go.pattern.negotiation_power = k.parse().unwrap();
            }
            if let Ok(a) = std::env::var("AUTO") {
                go.pattern.auto_darts = serde_json::from_str(&a).unwrap();
            }
            let g = match grade(&t, &body, Some(&obstacle), &name, &go) {
                Ok(g) => g,
                Err(e) => {
                    println!("{name}: ERROR {e}");
                    continue;
                }
            };
            let mut line = format!("{name:40}");
            for r in &g.pattern.reports {
                let d = &r.distortion;
                n += 1;
                sum += d.strain_p95;
                if d.strain_p95 > 0.03 {
                    above += 1;
                }
                worst = worst.max(d.strain_p95);
                let h = r.hotspot.as_ref().map(|h| h.near.clone()).unwrap_or_default();
                line += &format!(
                    " {}:{:.2}%/{:.2}/{:.1}({h})",
                    r.name,
                    d.strain_p95 * 100.0,
                    d.area_accuracy * 100.0,
                    d.strain_max * 100.0
                );
                line += &format!("[{}]", r.found_darts.len());
                if std::env::var("FABRIC").is_ok() {
                    let f = &r.fabric;
                    line += &format!(
                        " {{warp {:.2}% weft {:.2}% thread {:.2}% shear {:.1}°}}",
                        f.warp_p95 * 100.0,
                        f.weft_p95 * 100.0,
                        f.thread_p95 * 100.0,
                        f.shear_p95_deg
                    );
                }
                if std::env::var("DARTS").is_ok() {
                    for fd in &r.found_darts {
                        line += &format!(
                            " <{:.0}mm/{:.1}mm {:.2}→{:.2}>",
                            fd.length_mm,
                            fd.intake_mm,
                            fd.strain_p95_before * 100.0,
                            fd.strain_p95_after * 100.0
                        );
                    }
                }
            }
            if !g.pattern.darts_left_out.is_empty() {
                line += &format!(" out:{:?}", g.pattern.darts_left_out.iter().map(|d| d.0.clone()).collect::<Vec<_>>());
            }
            println!("{line}");
        }
    }
    println!(
        "pieces {n}, above 3 %: {above}, worst p95 {:.2} %, mean p95 {:.2} %",
        worst * 100.0,
        sum / n as f64 * 100.0
    );
}
