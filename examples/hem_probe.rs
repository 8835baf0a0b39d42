//! Development probe (issue #13): a template's hanging rings on a population
//! body — for every node at the lower end of a hang, its decoded position and
//! the body's horizontal section at its height (each loop's x and z range).
//!
//! `cargo run --release --example hem_probe -- straight-skirt 9`

use grade3d::body::derive::{derive_features, DeriveOptions};
use grade3d::geom::plane::Plane;
use grade3d::geom::slice::slice;
use grade3d::template::codec::decode;
use grade3d::template::library::builtin;

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let which = args.get(1).cloned().unwrap_or_else(|| "straight-skirt".into());
    let i: usize = args.get(2).and_then(|s| s.parse().ok()).unwrap_or(9);
    let model = grade3d::mannequin::model::BodyModel::embedded().unwrap();
    let b = &grade3d::mannequin::population::sample_population(40, 13)[i];
    let mesh = model.build(&b.params).unwrap();
    let lm = grade3d::mannequin::landmarks::hm08_landmarks(model, &mesh, &Default::default()).unwrap();
    let body = derive_features(mesh, &lm, &DeriveOptions::default()).unwrap();
    let t = builtin().unwrap().into_iter().find(|t| t.name.contains(which.as_str())).unwrap();
    let m = decode(&t, &body, Default::default()).unwrap();
    let mut lower: Vec<u32> = t.hangs.iter().map(|h| h.lower).collect();
    lower.sort_unstable();
    lower.dedup();
    println!("{} {}: hung {:?}", b.name, t.name, m.hung);
    for n in lower {
        let p = m.positions[n as usize];
        println!("node {n} ({}) at {:.0?} mm", t.nodes[n as usize].point.as_str(), (p * 1e3).to_array());
    }
    let y = t.hangs.first().map(|h| m.positions[h.lower as usize].y).unwrap_or(0.0);
    for s in slice(&body.mesh, &Plane { normal: glam::DVec3::Y, offset: y }) {
        let pts = &s.polyline.points;
        let r = |f: fn(&glam::DVec3) -> f64| {
            let v = pts.iter().map(f);
            (v.clone().fold(f64::MAX, f64::min) * 1e3, v.fold(f64::MIN, f64::max) * 1e3)
        };
        println!("section at y {:.0} mm: x {:.0?} z {:.0?}", y * 1e3, r(|p| p.x), r(|p| p.z));
    }
}
