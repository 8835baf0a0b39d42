//! Development probe (issue #13): grade built-in templates on bodies of the
//! population (tests/population.rs: seed 13) and print, per grade, the ease
//! at every declared girth (measured, expected, declared), what the surface
//! clearing leaves, and the worst piece's p95 strain.
//!
//! `cargo run --release --example ease_probe -- [template] [3,5,18] [scan|both]`

use grade3d::body::derive::{derive_features, DeriveOptions, Landmarks};
use grade3d::body::ease::{girth_ease, EaseOptions};
use grade3d::collide::cache::Obstacle;
use grade3d::collide::render::{GpuContext, RenderOptions};
use grade3d::geom::winding::{penetration_stats, WindingOptions, WindingTree};
use grade3d::mannequin::landmarks::hm08_landmarks;
use grade3d::mannequin::model::BodyModel;
use grade3d::mannequin::population::{sample_population, scan_like};
use grade3d::pipeline::{grade, GradeOptions};
use grade3d::template::library::builtin;

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let which = args.get(1).cloned().unwrap_or_default();
    let picked: Vec<usize> = args
        .get(2)
        .map(|s| s.split(',').filter_map(|n| n.trim().parse().ok()).collect())
        .unwrap_or_else(|| (0..40).collect());
    let forms = args.get(3).cloned().unwrap_or_else(|| "hm08".into());
    let gpu = GpuContext::new().unwrap();
    let library = builtin().unwrap();
    let model = BodyModel::embedded().unwrap();
    let population = sample_population(40, 13);
    for i in picked {
        let b = &population[i];
        let mesh = model.build(&b.params).unwrap();
        let lm = hm08_landmarks(model, &mesh, &Default::default()).unwrap();
        let mut jobs = Vec::new();
        if forms != "scan" {
            jobs.push((b.name.clone(), mesh.clone(), lm.clone()));
        }
        if forms != "hm08" {
            let scan = scan_like(&mesh, 60_000, 1e-3, 13 ^ i as u64).unwrap();
            let points_only = Landmarks { points: lm.points.clone(), curves: Default::default() };
            jobs.push((format!("{}-scan", b.name), scan, points_only));
        }
        for (name, mesh, lm) in jobs {
            let body = match derive_features(mesh, &lm, &DeriveOptions::default()) {
                Ok(b) => b,
                Err(e) => {
                    eprintln!("{name}: {e}");
                    continue;
                }
            };
            {
                use grade3d::body::vocab::PointId as P;
                let c = body.points[&P::Crotch].position;
                let th = body.points[&P::ThighLeft].position;
                let ti = body.points[&P::ThighLeftInner].position;
                eprintln!(
                    "{name}: crotch − thigh height {:.0} mm, crotch node to inner thigh point {:.0} mm",
                    (c.y - th.y) * 1e3,
                    (c - 0.015 * glam::DVec3::Y).distance(ti) * 1e3
                );
            }
            let maps = gpu.render(&body.mesh, &RenderOptions::default()).unwrap();
            let obstacle = Obstacle { maps, tree: WindingTree::new(&body.mesh, &WindingOptions::default()) };
            for t in library.iter().filter(|t| t.name.contains(which.as_str())) {
                let g = match grade(t, &body, Some(&obstacle), &name, &GradeOptions::default()) {
                    Ok(g) => g,
                    Err(e) => {
                        eprintln!("{} on {name}: {e}", t.name);
                        continue;
                    }
                };
                let pen = penetration_stats(&obstacle.tree, &g.mesh.positions.raw);
                let worst = g
                    .pattern
                    .reports
                    .iter()
                    .max_by(|a, b| a.distortion.strain_p95.total_cmp(&b.distortion.strain_p95))
                    .map(|r| format!("{} {:.2} %", r.name, r.distortion.strain_p95 * 100.0))
                    .unwrap_or_default();
                let cut = g.cut_mesh().unwrap();
                let ease: Vec<String> =
                    girth_ease(&body, &cut, t, &g.expected_ease_mm, &g.girth_lines, &EaseOptions::default())
                        .iter()
                        .map(|e| {
                            let flag = if (e.measured_mm - e.expected_mm).abs() > 5.0 { "!" } else { "" };
                            format!("{}{flag} {:.1}/{:.1}/{:.0}", e.girth, e.measured_mm, e.expected_mm, e.declared_mm)
                        })
                        .collect();
                eprintln!(
                    "{name} {}: pairs {}→{}, deepest {:.2} mm, p95 {worst}; ease {}",
                    t.name,
                    g.collision.surface.pairs_before,
                    g.collision.surface.pairs_after,
                    pen.deepest_m * 1e3,
                    ease.join(", ")
                );
            }
        }
    }
}
