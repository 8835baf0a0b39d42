use grade3d::body::derive::{derive_features, DeriveOptions};
use grade3d::mannequin::landmarks::hm08_landmarks;
use grade3d::mannequin::model::{BodyModel, MannequinParams};

fn main() {
    let model = BodyModel::embedded().unwrap();
    let mut p = MannequinParams::default();
    p.macros.gender = 0.0;
    let t = std::time::Instant::now();
    let mesh = model.build(&p).unwrap();
    println!("build {:?} bbox {:?}", t.elapsed(), mesh.aabb());
    let mut o = grade3d::mannequin::landmarks::Hm08LandmarkOptions::default();
    o.neck_base_tilt_deg = std::env::var("TILT").map(|s| s.parse().unwrap()).unwrap_or(25.0);
    let lm = hm08_landmarks(model, &mesh, &o).unwrap();
    for (k, v) in &lm.points {
        println!("lm {k}: {v:.3}");
    }
    let t = std::time::Instant::now();
    let fb = derive_features(mesh, &lm, &DeriveOptions::default());
    println!("derive {:?}", t.elapsed());
    match fb {
        Ok(fb) => {
            for (k, v) in grade3d::body::measure::measure(&fb, &Default::default()) {
                println!("measure {k}: {:.1} cm", v * 100.0);
            }
            for (k, c) in &fb.curves {
                println!("curve {k}: {} pts, len {:.3}", c.polyline.points.len(), c.polyline.length());
            }
            for (k, p) in &fb.points {
                println!("pt {k}: {:.3} triple {:.3} gap {:.2}mm", p.position, p.frame.triple(), p.crossing_gap * 1e3);
            }
        }
        Err(e) => println!("ERR {e}"),
    }
}
