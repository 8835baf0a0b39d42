//! Development probe (issue #14): a size chart graded as one run — the
//! base size fitted and graded first, every other size graded from its body
//! (`fit_graded`) with its dart plan carried — and
//! the grade judged as a set: nest steps (crossings, points outside the
//! next size), grade-step regularity scaled by the governing girth's chart
//! steps, and each piece's width per size.
//!
//! `cargo run --release --example grade_set_probe -- fixtures/size-charts/mens-36-46-in.csv trousers 42 [hip]`
//! (`NEST_DETAIL=1`: where consecutive sizes cross; `NO_BODY=1`: no collision; `POINTS=a,b`: feature points
//! and the nodes on them; `COLLISION=1`: what the collision steps did per size)

use std::collections::BTreeMap;

use grade3d::body::measure::MeasurementId;
use grade3d::collide::cache::Obstacle;
use grade3d::collide::render::{GpuContext, RenderOptions};
use grade3d::geom::winding::{WindingOptions, WindingTree};
use grade3d::mannequin::fit::{fit_graded, fit_size, FitOptions};
use grade3d::mannequin::model::BodyModel;
use grade3d::mannequin::size_chart::{parse_csv, SizeChartOptions};
use grade3d::pattern::grade::{grade_rules, nest_steps, nests, step_regularity, step_regularity_governed};
use grade3d::pattern::piece::PatternPiece;
use grade3d::pipeline::{grade_with_plan, GradeOptions};
use grade3d::template::library::builtin;

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let chart_path = args.get(1).cloned().unwrap_or_else(|| "fixtures/size-charts/mens-36-46-in.csv".into());
    let which = args.get(2).cloned().unwrap_or_else(|| "trousers".into());
    let base = args.get(3).cloned().unwrap_or_else(|| "42".into());
    let governing = match args.get(4).map(String::as_str).unwrap_or("hip") {
        "chest" => MeasurementId::ChestGirth,
        "bust" => MeasurementId::BustGirth,
        "waist" => MeasurementId::WaistGirth,
        _ => MeasurementId::HipGirth,
    };
    let chart = parse_csv(&std::fs::read_to_string(&chart_path).unwrap(), &SizeChartOptions::default()).unwrap();
    // `live:shift-dress`: the princess dress authored here, as the library would hold it
    let t = if which == "live:shift-dress" {
        let design = grade3d::template::library::reference_body().unwrap();
        // DOPTS=json: ShiftDressOptions over the library's (princess) ones
        let mut o = serde_json::to_value(grade3d::template::drawn::ShiftDressOptions::princess()).unwrap();
        if let Ok(j) = std::env::var("DOPTS") {
            let extra: serde_json::Value = serde_json::from_str(&j).unwrap();
            for (k, v) in extra.as_object().unwrap() {
                o[k] = v.clone();
            }
        }
        grade3d::template::drawn::shift_dress(&design, &serde_json::from_value(o).unwrap()).unwrap()
    } else {
        builtin().unwrap().into_iter().find(|t| t.name.contains(which.as_str())).unwrap()
    };
    let gpu = GpuContext::new().unwrap();
    let model = BodyModel::embedded().unwrap();
    let fit_opts = FitOptions::for_sex(chart.sex);
    let each = std::env::var("EACH").is_ok();
    let base_row = chart.rows.iter().position(|r| r.size == base).unwrap();
    let order: Vec<usize> = std::iter::once(base_row).chain((0..chart.rows.len()).filter(|&i| i != base_row)).collect();
    let mut plan = None;
    // INDEPENDENT=1: every size fitted on its own (phases 1 and 2), not graded from the base size
    let fit_opts = FitOptions { independent_sizes: std::env::var("INDEPENDENT").is_ok(), ..fit_opts };
    let mut base_fit: Option<grade3d::mannequin::fit::FittedMannequin> = None;
    let mut by_row: BTreeMap<usize, Vec<PatternPiece>> = BTreeMap::new();
    for i in order {
        let row = &chart.rows[i];
        let fitted = match &base_fit {
            Some(b) if !fit_opts.independent_sizes => fit_graded(model, b, row, &fit_opts).unwrap(),
            _ => fit_size(model, row, &fit_opts).unwrap(),
        };
        if base_fit.is_none() {
            base_fit = Some(fitted.clone());
        }
        if std::env::var("RESIDUALS").is_ok() {
            let worst = fitted.residuals.values().map(|r| r.error_mm().abs()).fold(0.0, f64::max);
            println!("{} worst residual {worst:.2} mm ({} rounds)", row.size, fitted.scaling_rounds);
        }
        let body = &fitted.body;
        // MEASURE=a,b: the fitted body's measurements (mm)
        if let Ok(names) = std::env::var("MEASURE") {
            let m = grade3d::body::measure::measure(body, &Default::default());
            let shown: Vec<String> = m
                .iter()
                .filter(|(id, _)| names.split(',').any(|n| n == id.as_str()))
                .map(|(id, v)| format!("{id} {:.1}", v * 1e3))
                .collect();
            println!("{} measured: {}", row.size, shown.join(", "));
        }
        if std::env::var("PARAMS").is_ok() {
            println!("{} params {:?}", row.size, serde_json::to_string(&fitted.params).unwrap());
            println!("{} scales {:?}", row.size, fitted.profile_scales);
        }
        let maps = gpu.render(&body.mesh, &RenderOptions::default()).unwrap();
        let obstacle = Obstacle { maps, tree: WindingTree::new(&body.mesh, &WindingOptions::default()) };
        // INSIDE=mm: the template's nodes that decode deeper than that inside this size's body,
        // with what places them (the ones `refine::clear::clear_coarse` then moves)
        if let Some(limit) = std::env::var("INSIDE").ok().and_then(|v| v.parse::<f64>().ok()) {
            let m = grade3d::template::codec::decode(&t, body, t.defaults.relocation).unwrap();
            let index = grade3d::geom::query::SphereIndex::new(&body.mesh);
            let mut deep = Vec::new();
            for (i, &p) in m.positions.iter().enumerate() {
                if obstacle.tree.is_inside(p) {
                    let d = index.closest_point(&body.mesh, p).point.distance(p) * 1e3;
                    if d > limit {
                        let i32_ = i as u32;
                        let kind = if t.between.iter().any(|b| b.node == i32_) {
                            "between"
                        } else if t.below.iter().any(|b| b.node == i32_) {
                            "below"
                        } else if t.on_curve.iter().any(|c| c.node == i32_) {
                            "on_curve"
                        } else {
                            "eq1"
                        };
                        deep.push(format!("{i} {kind} {} {d:.1}", t.nodes[i].point));
                    }
                }
            }
            println!("{} inside by more than {limit} mm: {}", row.size, deep.join("; "));
        }
        // PFLAT=json: the pattern's flattening options (FlattenOptions)
        let mut go = GradeOptions::default();
        if let Ok(f) = std::env::var("PFLAT") {
            go.pattern.flatten = serde_json::from_str(&f).unwrap();
        }
        // NEG_POWER=k: the seam negotiation's weight power (PatternOptions::negotiation_power)
        if let Some(k) = std::env::var("NEG_POWER").ok().and_then(|v| v.parse().ok()) {
            go.pattern.negotiation_power = k;
        }
        // FREE_SEAMS=1: the seams not negotiated: each held at its 3D length
        if std::env::var("FREE_SEAMS").is_ok() {
            go.pattern.negotiate_seams = false;
        }
        // NO_BODY=1: graded without the body as an obstacle (no collision steps)
        let obstacle = (std::env::var("NO_BODY").is_err()).then_some(&obstacle);
        let g = grade_with_plan(&t, body, obstacle, &row.size, &go, plan.as_ref()).unwrap();
        // POINTS=a,b: body feature points and the garment's nodes on them (cut positions, mm)
        if let Ok(names) = std::env::var("POINTS") {
            for name in names.split(',') {
                let bp = body.points.iter().find(|(id, _)| id.as_str() == name).map(|(_, p)| p.position * 1e3);
                let nodes: Vec<String> = t
                    .nodes
                    .iter()
                    .enumerate()
                    .filter(|(_, n)| n.point.as_str() == name)
                    .map(|(i, _)| {
                        let q = g.cut_positions[grade3d::refine::lineage::node_vertex(i as u32)] * 1e3;
                        format!("[{:.1},{:.1},{:.1}]", q.x, q.y, q.z)
                    })
                    .collect();
                println!(
                    "  {} {name}: body {:?} garment {}",
                    row.size,
                    bp.map(|p| [p.x.round(), p.y.round(), p.z.round()]),
                    nodes.join(" ")
                );
                if let Some((_, fp)) = body.points.iter().find(|(id, _)| id.as_str() == name) {
                    let f = &fp.frame;
                    println!(
                        "     frame t1 {:.3?} t2 {:.3?} n {:.3?}",
                        f.t1.to_array(),
                        f.t2.to_array(),
                        f.n.to_array()
                    );
                }
            }
        }
        let line: Vec<String> = g
            .pattern
            .reports
            .iter()
            .map(|r| {
                // FLAT_DETAIL=1: the flattening's iterations, convergence and fallback
                let detail = if std::env::var("FLAT_DETAIL").is_ok() {
                    format!(" it{} c{} f{:?}", r.iterations, r.converged, r.fallback)
                } else {
                    String::new()
                };
                format!("{} {:.2}% [{}]{detail}", r.name, r.distortion.strain_p95 * 100.0, r.found_darts.len())
            })
            .collect();
        println!("{}: {}", row.size, line.join(", "));
        // SEAMS=piece: the 3D and sewn lengths of that piece's seams (mm)
        if let Ok(piece) = std::env::var("SEAMS") {
            for s in g.pattern.seams.iter().filter(|s| s.piece_a == piece || s.piece_b == piece) {
                println!(
                    "  {} seam {} ({}+{}): 3D {:.1}, sewn {:.1} / {:.1}",
                    row.size, s.name, s.piece_a, s.piece_b, s.length_3d_mm, s.length_a_mm, s.length_b_mm
                );
            }
        }
        // COLLISION=1: what the collision steps did (a node pushed out of the arm jumps the grade)
        if std::env::var("COLLISION").is_ok() {
            let c = &g.collision;
            println!(
                "  {} pushed {}, refused {}, settled {}, fixed settled {}; {:?}; surface lifts {}, largest {:.1} mm",
                row.size,
                c.pushed,
                c.refused,
                c.settled,
                c.fixed_settled,
                c.coarse,
                c.surface.lifts,
                c.surface.max_moved_mm
            );
        }
        if plan.is_none() && !each {
            plan = Some(g.pattern.dart_plan.clone());
        }
        by_row.insert(i, g.pattern.pieces);
    }
    let mut sizes: Vec<(String, Vec<PatternPiece>)> =
        by_row.into_iter().map(|(i, p)| (chart.rows[i].size.clone(), p)).collect();
    // NOTRUE=1: the nest as cut, not trued at its corners
    if std::env::var("NOTRUE").is_err() {
        let before = seam_runs(&sizes);
        let cut = sizes.clone();
        let b = sizes.iter().position(|(s, _)| *s == base).unwrap();
        let topts: grade3d::pattern::true_up::TrueOptions =
            std::env::var("TRUE_OPTS").map(|j| serde_json::from_str(&j).unwrap()).unwrap_or_default();
        let report = grade3d::pattern::true_up::true_nest(&mut sizes, b, &topts);
        let after = seam_runs(&sizes);
        let worst =
            before.iter().zip(&after).map(|(x, y)| (x.0.clone(), (x.1 - y.1).abs())).max_by(|x, y| x.1.total_cmp(&y.1));
        println!(
            "trued: {} piece-sizes moved, largest {:.2} mm, {} corners left, as cut {:?}; worst seam-side length mismatch change {:?}",
            report.moved.len(),
            report.largest_move_mm,
            report.left,
            report.as_cut,
            worst
        );
        for m in &report.moved {
            // the grade point truing moved the most in that piece and size
            let most = cut
                .iter()
                .zip(&sizes)
                .filter(|((s, _), _)| *s == m.size)
                .flat_map(|((_, a), (_, b))| a.iter().zip(b).filter(|(p, _)| p.name == m.piece))
                .flat_map(|(p, q)| {
                    p.grade_points.iter().zip(&q.grade_points).map(|(g, h)| (g.label.clone(), g.at.distance(h.at)))
                })
                .max_by(|x, y| x.1.total_cmp(&y.1))
                .map_or(String::new(), |(l, d)| format!("; most at {l} ({d:.2} mm)"));
            println!("  trued {} {}: {} corners, {:.2} mm{most}", m.piece, m.size, m.corners, m.moved_mm);
        }
    }
    // STACK=centroid: every piece restacked at its sew line's area centroid (experiment)
    if std::env::var("STACK").is_ok() {
        for (_, pieces) in sizes.iter_mut() {
            for p in pieces.iter_mut() {
                let n = p.sew_line.len();
                let (mut a, mut c) = (0.0, glam::DVec2::ZERO);
                for i in 0..n {
                    let (u, v) = (p.sew_line[i], p.sew_line[(i + 1) % n]);
                    let cr = u.perp_dot(v);
                    a += cr;
                    c += (u + v) * cr;
                }
                let c = c / (3.0 * a);
                for q in p.sew_line.iter_mut() {
                    *q -= c;
                }
                for g in p.grade_points.iter_mut() {
                    g.at -= c;
                }
            }
        }
    }
    let nest = nests(&sizes).unwrap();
    // NEST_SVG=path: the trued nest drawn
    if let Ok(path) = std::env::var("NEST_SVG") {
        std::fs::write(path, grade3d::pattern::export::svg::nest_svg(&t.name, &nest, &Default::default())).unwrap();
    }
    for (piece, all) in &nest {
        let widths: Vec<String> = all
            .iter()
            .map(|p| {
                let xs = p.sew_line.iter().map(|q| q.x);
                format!("{:.0}", xs.clone().fold(f64::MIN, f64::max) - xs.fold(f64::MAX, f64::min))
            })
            .collect();
        println!("{piece} widths: {}", widths.join(" "));
        let counts: Vec<String> = all.iter().map(|p| format!("{}/{}", p.sew_line.len(), p.corners.len())).collect();
        println!("{piece} sew-line points/corners: {}", counts.join(" "));
    }
    for st in nest_steps(&nest) {
        println!("  {} {}→{}: crossings {}, outside {}", st.piece, st.smaller, st.larger, st.crossings, st.outside);
    }
    // CORNER=piece:label: the sew line of every size within 40 mm of that grade point
    if let Ok(spec) = std::env::var("CORNER") {
        let (pn, label) = spec.split_once(':').unwrap();
        for (piece, all) in nest.iter().filter(|(n, _)| n == pn) {
            for p in all {
                let g = p.grade_points.iter().find(|g| g.label == label).unwrap();
                let near: Vec<String> = p
                    .sew_line
                    .iter()
                    .filter(|q| q.distance(g.at) < 40.0)
                    .map(|q| format!("[{:.1},{:.1}]", q.x, q.y))
                    .collect();
                println!("    {piece} {} {label} at [{:.1},{:.1}]: {}", p.size, g.at.x, g.at.y, near.join(" "));
            }
        }
    }
    // NEST_DETAIL=1: where the outlines of consecutive sizes cross, by the nearest grade point
    if std::env::var("NEST_DETAIL").is_ok() {
        for (piece, all) in &nest {
            for w in all.windows(2) {
                let (a, b) = (&w[0], &w[1]);
                let n = a.sew_line.len();
                let m = b.sew_line.len();
                let mut at = Vec::new();
                for i in 0..n {
                    let (p, q) = (a.sew_line[i], a.sew_line[(i + 1) % n]);
                    for j in 0..m {
                        let (r, s) = (b.sew_line[j], b.sew_line[(j + 1) % m]);
                        if grade3d::geom::polyline::segments_cross(p, q, r, s) {
                            let g = a
                                .grade_points
                                .iter()
                                .min_by(|u, v| u.at.distance(p).total_cmp(&v.at.distance(p)))
                                .map(|g| format!("{} ({:.0} mm)", g.label, g.at.distance(p)))
                                .unwrap_or_default();
                            at.push(format!("[{:.0},{:.0}] near {g}", p.x, p.y));
                        }
                    }
                }
                // the farthest sew-line point of the smaller size outside the larger one, mm
                let far = a
                    .sew_line
                    .iter()
                    .filter(|&&p| !grade3d::geom::polyline::point_in_polygon(&b.sew_line, p))
                    .map(|&p| (grade3d::geom::polyline::distance_to_polygon(&b.sew_line, p), p))
                    .max_by(|x, y| x.0.total_cmp(&y.0));
                let far = far.map_or(String::new(), |(d, p)| format!("{d:.2} mm at [{:.0},{:.0}]", p.x, p.y));
                println!("    {piece} {}→{}: farthest outside {far}; {}", a.size, b.size, at.join("; "));
            }
        }
    }
    let rules = grade_rules(&t.name, &sizes, &base).unwrap();
    let steps = chart.steps(governing).unwrap_or_default();
    println!("chart steps of {governing:?}, m: {steps:?}");
    // each grade point read against the chart steps of its own girth, where the chart
    // gives it (ONE_GIRTH=1: every point against the one governing girth)
    let reg = if std::env::var("ONE_GIRTH").is_ok() {
        step_regularity(&rules, Some(&steps))
    } else {
        step_regularity_governed(&rules, &t, |m| chart.steps(m))
    };
    let over = reg.iter().filter(|r| r.worst_mm > r.allowed_mm).count();
    let signs: usize = reg.iter().map(|r| r.sign_changes).sum();
    println!("grade steps: {over} of {} points over the bar, {signs} sign changes", reg.len());
    for r in &reg {
        let s: Vec<String> = r.steps.iter().map(|v| format!("({:.1},{:.1})", v.x, v.y)).collect();
        let flag = if r.worst_mm > r.allowed_mm || r.sign_changes > 0 { "!" } else { " " };
        println!(
            "{flag} {} {}: worst {:.1} / {:.1} mm, signs {}: {}",
            r.piece,
            r.label,
            r.worst_mm,
            r.allowed_mm,
            r.sign_changes,
            s.join(" ")
        );
    }
}

/// Per size and run shared by two pieces (the same two consecutive corner
/// nodes): the difference of the two sides' run lengths, mm.
fn seam_runs(sizes: &[(String, Vec<PatternPiece>)]) -> Vec<(String, f64)> {
    let mut out = Vec::new();
    for (size, pieces) in sizes {
        let mut runs: BTreeMap<(u32, u32), Vec<(String, f64)>> = BTreeMap::new();
        for p in pieces {
            let a = grade3d::pattern::true_up::anchors(p);
            let n = p.sew_line.len();
            for k in 0..a.len() {
                let (i, u) = a[k];
                let (j, v) = a[(k + 1) % a.len()];
                let mut len = 0.0;
                let mut q = i;
                while q != j {
                    len += p.sew_line[q].distance(p.sew_line[(q + 1) % n]);
                    q = (q + 1) % n;
                }
                runs.entry((u.min(v), u.max(v))).or_default().push((p.name.clone(), len));
            }
        }
        for ((u, v), sides) in runs {
            if sides.len() == 2 {
                out.push((format!("{size} {}/{} {u}-{v}", sides[0].0, sides[1].0), sides[0].1 - sides[1].1));
            }
        }
    }
    out
}
