//! Development probe (issue #18): one library template on the 12 ASTM size
//! mannequins of `fixtures/astm`, graded as the pattern test grades them
//! (size 8 first, its dart plan carried to the other sizes, the nest trued
//! outwards from it), and the grade read as the test reads it: each grade
//! point's step regularity against its own governing girths.
//!
//! `cargo run --release --example astm_run_probe -- a-line`
//! (`LABEL=piece:label`: that grade point's deltas and steps per size;
//! `SEAMS=piece`: the 3D and sewn lengths of that piece's seams per size;
//! `FREE_SEAMS=1`: every seam held at its 3D length)

use std::collections::BTreeMap;
use std::path::Path;

use grade3d::body::derive::{derive_features, DeriveOptions};
use grade3d::body::measure::{measure, MeasureOptions, MeasurementId};
use grade3d::collide::cache::Obstacle;
use grade3d::collide::render::{RenderOptions, Renderer, RendererChoice};
use grade3d::collide::DepthRenderer;
use grade3d::geom::winding::{WindingOptions, WindingTree};
use grade3d::io::gltf::{read_mesh, GltfReadOptions};
use grade3d::io::landmarks::parse_landmarks;
use grade3d::pattern::grade::{grade_rules, step_regularity_governed};
use grade3d::pattern::piece::PatternPiece;
use grade3d::pattern::true_up::{true_nest, TrueOptions};
use grade3d::pipeline::{grade_with_plan, GradeOptions};
use grade3d::template::library::builtin;

/// ASTM order.
const SIZES: [&str; 12] = ["00", "0", "2", "4", "6", "8", "10", "12", "14", "16", "18", "20"];

fn main() {
    let which = std::env::args().nth(1).unwrap_or_else(|| "a-line".into());
    let t = builtin().unwrap().into_iter().find(|t| t.name.contains(which.as_str())).unwrap();
    let renderer = Renderer::new(RendererChoice::Auto).unwrap();
    let dir = Path::new("fixtures/astm");
    let mut go = GradeOptions::default();
    if std::env::var("FREE_SEAMS").is_ok() {
        go.pattern.negotiate_seams = false;
    }
    let order: Vec<&str> = std::iter::once("8").chain(SIZES.iter().copied().filter(|s| *s != "8")).collect();
    let mut plan = None;
    let mut by_size: BTreeMap<usize, (String, Vec<PatternPiece>)> = BTreeMap::new();
    let mut chart = BTreeMap::new();
    for s in order {
        let n = format!("size-{s}");
        let mesh =
            read_mesh(&std::fs::read(dir.join(format!("{n}.glb"))).unwrap(), &GltfReadOptions::default()).unwrap();
        let lm = parse_landmarks(&std::fs::read_to_string(dir.join(format!("{n}.landmarks.json"))).unwrap()).unwrap();
        let body = derive_features(mesh, &lm, &DeriveOptions::default()).unwrap();
        chart.insert(n.clone(), measure(&body, &MeasureOptions::default()));
        let maps = renderer.depth_maps(&body.mesh, &RenderOptions::default()).unwrap();
        let obstacle = Obstacle { maps, tree: WindingTree::new(&body.mesh, &WindingOptions::default()) };
        let g = grade_with_plan(&t, &body, Some(&obstacle), &n, &go, plan.as_ref()).unwrap();
        if s == "8" {
            plan = Some(g.pattern.dart_plan.clone());
        }
        if let Ok(piece) = std::env::var("SEAMS") {
            for sm in g.pattern.seams.iter().filter(|sm| sm.piece_a == piece || sm.piece_b == piece) {
                println!(
                    "  {n} seam {} ({}+{}): 3D {:.2}, sewn {:.2} / {:.2}, ratio {:.5}",
                    sm.name,
                    sm.piece_a,
                    sm.piece_b,
                    sm.length_3d_mm,
                    sm.length_a_mm,
                    sm.length_b_mm,
                    sm.length_a_mm / sm.length_3d_mm
                );
            }
        }
        // NODE=i: template node i's position as cut (mm) and its feature point on the body
        if let Some(i) = std::env::var("NODE").ok().and_then(|v| v.parse::<u32>().ok()) {
            let q = g.cut_positions[grade3d::refine::lineage::node_vertex(i)] * 1e3;
            let name = t.nodes[i as usize].point.as_str();
            let bp = body.points.iter().find(|(id, _)| id.as_str() == name).map(|(_, p)| p.position * 1e3);
            if let Some((_, fp)) = body.points.iter().find(|(id, _)| id.as_str() == name) {
                let f = &fp.frame;
                let deg = |v: glam::DVec3| [v.x.atan2(v.z).to_degrees() as f32, v.y.asin().to_degrees() as f32];
                println!("  {n} frame (azimuth, elevation °): t1 {:?} t2 {:?} n {:?}", deg(f.t1), deg(f.t2), deg(f.n));
            }
            let m0 =
                grade3d::template::codec::decode(&t, &body, grade3d::template::format::Relocation::Eq1Frame).unwrap();
            let d = m0.positions[i as usize] * 1e3;
            println!("  {n} node {i} decoded [{:.1}, {:.1}, {:.1}]", d.x, d.y, d.z);
            println!(
                "  {n} node {i} ({name}): garment [{:.1}, {:.1}, {:.1}] body {:?}",
                q.x,
                q.y,
                q.z,
                bp.map(|p| [p.x as f32, p.y as f32, p.z as f32])
            );
        }
        // BODY_POINT=a,b: body feature points (mm)
        if let Ok(names) = std::env::var("BODY_POINT") {
            for name in names.split(',') {
                if let Some((_, fp)) = body.points.iter().find(|(id, _)| id.as_str() == name) {
                    let p = fp.position * 1e3;
                    println!("  {n} {name} [{:.1}, {:.1}, {:.1}]", p.x, p.y, p.z);
                }
            }
        }
        let k = SIZES.iter().position(|x| *x == s).unwrap();
        by_size.insert(k, (n, g.pattern.pieces.clone()));
    }
    let mut sizes: Vec<(String, Vec<PatternPiece>)> = by_size.into_values().collect();
    let base = sizes.iter().position(|(s, _)| s == "size-8").unwrap();
    let trued = true_nest(&mut sizes, base, &TrueOptions::default());
    println!("truing moved {} piece-sizes, at most {:.2} mm", trued.moved.len(), trued.largest_move_mm);
    let rules = grade_rules(&t.name, &sizes, "size-8").unwrap();
    let steps_of = |m: MeasurementId| -> Option<Vec<f64>> {
        let girths: Option<Vec<f64>> = sizes.iter().map(|(s, _)| chart[s].get(&m).copied()).collect();
        girths.map(|g| g.windows(2).map(|w| w[1] - w[0]).collect())
    };
    let own = step_regularity_governed(&rules, &t, steps_of);
    let over: Vec<_> = own.iter().filter(|r| r.worst_mm > r.allowed_mm || r.sign_changes > 0).collect();
    println!("{} of {} grade points over the bar", over.len(), own.len());
    for r in &own {
        let margin = r.allowed_mm - r.worst_mm;
        if margin < 0.3 || r.sign_changes > 0 {
            println!(
                "  {} {}: worst {:.2} (allowed {:.2}), {} run back",
                r.piece, r.label, r.worst_mm, r.allowed_mm, r.sign_changes
            );
        }
    }
    if let Ok(want) = std::env::var("LABEL") {
        let (piece, label) = want.split_once(':').unwrap();
        for p in rules.pieces.iter().filter(|p| p.piece == piece) {
            for r in p.rules.iter().filter(|r| r.label == label) {
                for (d, (s, _)) in r.deltas.iter().zip(&sizes) {
                    println!("  {s}: delta [{:.2}, {:.2}]", d.x, d.y);
                }
            }
        }
        for p in rules.pieces.iter().filter(|p| p.piece == piece) {
            for r in p.rules.iter().filter(|r| r.label == label) {
                for m in grade3d::pattern::grade::governing_girths(&t, r.node).into_iter().chain([
                    MeasurementId::HipGirth,
                    MeasurementId::ThighGirth,
                    MeasurementId::WaistGirth,
                ]) {
                    println!(
                        "  node {} governed by {m:?}: chart steps {:?}",
                        r.node,
                        steps_of(m).map(|v| v.iter().map(|w| (w * 1e4).round() / 10.0).collect::<Vec<_>>())
                    );
                }
            }
        }
        for r in own.iter().filter(|r| r.piece == piece && r.label == label) {
            for st in &r.steps {
                println!("  scaled step [{:.2}, {:.2}]", st.x, st.y);
            }
        }
    }
}
