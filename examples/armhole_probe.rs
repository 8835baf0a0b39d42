//! Development probe: where the bodice's armhole nodes decode on a
//! population body (`popNN` or `popNN-scan`), along the armscye (`OnCurve`)
//! and by Eq. (1) alone, and how deep inside the body each lies.
//!
//! `cargo run --release --example armhole_probe -- pop31-scan`

use grade3d::body::derive::{derive_features, DeriveOptions};
use grade3d::geom::winding::{WindingOptions, WindingTree};
use grade3d::template::codec::decode;
use grade3d::template::format::{Relocation, Template};
use grade3d::template::library::builtin;

fn main() {
    let only = std::env::args().nth(1).unwrap_or_else(|| "pop31-scan".into());
    let scan = only.ends_with("-scan");
    let i: usize = only.trim_start_matches("pop").trim_end_matches("-scan").parse().unwrap();
    let model = grade3d::mannequin::model::BodyModel::embedded().unwrap();
    let b = &grade3d::mannequin::population::sample_population(40, 13)[i];
    let mesh = model.build(&b.params).unwrap();
    let mut lm = grade3d::mannequin::landmarks::hm08_landmarks(model, &mesh, &Default::default()).unwrap();
    let mesh = if scan {
        lm.curves.clear();
        grade3d::mannequin::population::scan_like(&mesh, 60_000, 1e-3, 13 ^ i as u64).unwrap()
    } else {
        mesh
    };
    let body = derive_features(mesh, &lm, &DeriveOptions::default()).unwrap();
    let tree = WindingTree::new(&body.mesh, &WindingOptions::default());
    let t = builtin().unwrap().into_iter().find(|t| t.name == "fitted-bodice").unwrap();
    let plain = Template { on_curve: vec![], ..t.clone() };
    let with = decode(&t, &body, Relocation::Eq1Frame).unwrap();
    let without = decode(&plain, &body, Relocation::Eq1Frame).unwrap();
    for c in &t.on_curve {
        let curve = &body.curves[&c.curve].polyline;
        let depth = |p: glam::DVec3| {
            let q = grade3d::geom::query::closest_point(&body.mesh, p).point;
            let inside = tree.winding_number_exact(p) > 0.5;
            (if inside { 1.0 } else { -1.0 }) * p.distance(q) * 1e3
        };
        let (a, e) = (with.positions[c.node as usize], without.positions[c.node as usize]);
        println!(
            "node {} ({} via {}): on curve {:.0?} depth {:.1} mm; Eq. (1) {:.0?} depth {:.1} mm; apart {:.1} mm; curve {:.0} mm, {} points",
            c.node,
            c.curve,
            c.via,
            (a * 1e3).to_array(),
            depth(a),
            (e * 1e3).to_array(),
            depth(e),
            a.distance(e) * 1e3,
            curve.length() * 1e3,
            curve.points.len()
        );
    }
}
