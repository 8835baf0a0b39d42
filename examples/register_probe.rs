//! Development probe (issue #17): automatic landmarks on scan-like
//! population bodies against the hm08 topology's own, per landmark; the
//! registration's time; and where the error comes from — the landmarks of
//! the *fitted* parameters' model against the true one's, beside the
//! distance between the two surfaces (two parameter sets that give the same
//! surface place MakeHuman's rings differently).
//!
//! `cargo run --release --example register_probe -- [BODIES] [SAMPLES] [ROUNDS] [LM_STEPS]`

use std::collections::BTreeMap;
use std::time::Instant;

use grade3d::body::vocab::PointId;
use grade3d::geom::winding::{WindingOptions, WindingTree};
use grade3d::mannequin::landmarks::hm08_landmarks;
use grade3d::mannequin::model::BodyModel;
use grade3d::mannequin::population::{sample_population, scan_like};
use grade3d::mannequin::register::{register, RegisterOptions};

fn main() {
    let arg = |i: usize, d: usize| std::env::args().nth(i).and_then(|a| a.parse().ok()).unwrap_or(d);
    let d = RegisterOptions::default();
    let (bodies, samples, rounds, lm_steps) = (arg(1, 10), arg(2, d.samples), arg(3, d.rounds), arg(4, d.lm_steps));
    let opts = RegisterOptions { samples, rounds, lm_steps, ..d };
    let model = BodyModel::embedded().unwrap();
    let mut err: BTreeMap<PointId, Vec<f64>> = BTreeMap::new();
    let mut shape_err: BTreeMap<PointId, Vec<f64>> = BTreeMap::new();
    let mut times = Vec::new();
    for (i, b) in sample_population(40, 13).into_iter().take(bodies).enumerate() {
        let mesh = model.build(&b.params).unwrap();
        let truth = hm08_landmarks(model, &mesh, &Default::default()).unwrap().points;
        let scan = scan_like(&mesh, 60_000, 1e-3, 13 ^ i as u64).unwrap();
        let t = Instant::now();
        let reg = register(model, &scan, &[], &opts).unwrap();
        let ms = t.elapsed().as_secs_f64() * 1e3;
        times.push(ms);
        // the fitted parameters' own model against the true one
        let fitted = model.build(&reg.params).unwrap();
        let tree = WindingTree::new(&mesh, &WindingOptions::default());
        let d: Vec<f64> = fitted.positions().iter().map(|&p| tree.closest_point(p).2 * 1e3).collect();
        let rms = (d.iter().map(|x| x * x).sum::<f64>() / d.len() as f64).sqrt();
        let on_fitted = hm08_landmarks(model, &fitted, &Default::default()).unwrap().points;
        let mut worst = (0.0, PointId::Crotch);
        for (id, p) in &truth {
            let e = reg.landmarks.points[id].distance(*p) * 1e3;
            err.entry(*id).or_default().push(e);
            shape_err.entry(*id).or_default().push(on_fitted[id].distance(*p) * 1e3);
            if e > worst.0 {
                worst = (e, *id);
            }
        }
        println!(
            "{:26} {ms:6.0} ms  rms {:.2} mm  shape {:.2} mm  fitted model vs true model {rms:.2} mm RMS (after its own translation)  worst {} {:.1} mm",
            b.name, reg.report.rms_mm, reg.report.shape_rms_mm, worst.1, worst.0
        );
    }
    let q = |v: &mut Vec<f64>, f: f64| {
        v.sort_by(f64::total_cmp);
        v[((v.len() - 1) as f64 * f).round() as usize]
    };
    let mut all: Vec<f64> = err.values().flatten().copied().collect();
    println!(
        "registration {:.0} ms median, {:.0} ms max; all landmarks: median {:.1} mm, p95 {:.1} mm",
        q(&mut times, 0.5),
        q(&mut times, 1.0),
        q(&mut all, 0.5),
        q(&mut all, 0.95)
    );
    println!("{:18} {:>8} {:>8}   {:>14}", "landmark", "median", "p95", "fitted model median");
    for (id, v) in &mut err {
        let s = shape_err.get_mut(id).unwrap();
        println!("{:18} {:8.1} {:8.1}   {:14.1}", id.as_str(), q(v, 0.5), q(v, 0.95), q(s, 0.5));
    }
}
