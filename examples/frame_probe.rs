//! Development probe (issue #13): the Eq. (1) frames of a population body's
//! feature points, flattest first.
//!
//! `cargo run --release --example frame_probe -- popNN [count]`

use grade3d::body::derive::{derive_features, DeriveOptions};

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let i: usize = args.get(1).and_then(|s| s.trim_start_matches("pop").parse().ok()).unwrap_or(36);
    let count: usize = args.get(2).and_then(|s| s.parse().ok()).unwrap_or(8);
    let model = grade3d::mannequin::model::BodyModel::embedded().unwrap();
    let b = &grade3d::mannequin::population::sample_population(40, 13)[i];
    let mesh = model.build(&b.params).unwrap();
    let lm = grade3d::mannequin::landmarks::hm08_landmarks(model, &mesh, &Default::default()).unwrap();
    let opts = DeriveOptions { min_frame_triple: 0.0, ..Default::default() };
    let body = derive_features(mesh, &lm, &opts).unwrap();
    let mut frames: Vec<_> = body.points.iter().map(|(id, p)| (p.frame.triple().abs(), *id, p.frame)).collect();
    frames.sort_by(|a, b| a.0.total_cmp(&b.0));
    println!("{} {:?}", b.name, b.params);
    if let Ok(near) = std::env::var("NEAR") {
        let def = grade3d::body::vocab::POINTS.iter().find(|d| d.id.as_str() == near).unwrap();
        let q = body.points[&def.id].position;
        println!("{near} at {:.1?} mm", (q * 1e3).to_array());
        for c in [def.f1, def.f2] {
            let pl = &body.curves[&c].polyline;
            let close: Vec<String> = pl
                .points
                .iter()
                .filter(|p| p.distance(q) < 0.04)
                .map(|p| format!("{:.0?}", ((*p - q) * 1e3).to_array()))
                .collect();
            println!("  {c:?} ({} points): {}", pl.points.len(), close.join(" "));
        }
    }
    for (t, id, f) in frames.into_iter().take(count) {
        println!(
            "{id:?} triple {t:.3} t1 {:.2?} t2 {:.2?} n {:.2?} t1.t2 {:.2} n.(t1xt2)^ {:.2}",
            f.t1.to_array(),
            f.t2.to_array(),
            f.n.to_array(),
            f.t1.dot(f.t2),
            f.n.dot(f.t1.cross(f.t2).normalize())
        );
    }
}
