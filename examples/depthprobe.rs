//! Probe: render depth maps of a fixture body and check pixels against ray casting.
use glam::DVec3;
use grade3d::collide::render::{pixel_point, GpuContext, RenderOptions};

fn main() {
    let t = std::time::Instant::now();
    let gpu = GpuContext::new().unwrap();
    println!("adapter {:?} in {:?}", gpu.adapter(), t.elapsed());
    let mesh = grade3d::io::gltf::read_mesh(
        &std::fs::read("fixtures/bodies/female-average-caucasian.glb").unwrap(),
        &Default::default(),
    )
    .unwrap();
    for res in [512u32, 1024] {
        let t = std::time::Instant::now();
        let maps = gpu.render(&mesh, &RenderOptions { resolution: res, ..Default::default() }).unwrap();
        println!("res {res}: {} views in {:?}", maps.len(), t.elapsed());
        let m = &maps[0];
        let filled = m.front.iter().filter(|x| x.is_finite()).count();
        println!("filled {filled}");
        // brute-force check on a grid of pixels
        let mut worst = 0.0f64;
        let mut n = 0;
        for y in (0..res).step_by((res / 32) as usize) {
            for x in (0..res).step_by((res / 32) as usize) {
                if let Some(p) = pixel_point(m, x, y) {
                    // ray along -d from far in front
                    let o = p + m.view.d * 10.0;
                    let mut best = f64::NEG_INFINITY;
                    for f in 0..mesh.face_count() {
                        let [a, b, c] = mesh.corners(grade3d::geom::mesh::FaceId(f as u32));
                        let to2 = |q: DVec3| glam::DVec2::new(q.dot(m.view.u), q.dot(m.view.w));
                        let (pa, pb, pc, po) = (to2(a), to2(b), to2(c), to2(o));
                        let area = (pb - pa).perp_dot(pc - pa);
                        if area.abs() < 1e-18 {
                            continue;
                        }
                        let w0 = (pb - po).perp_dot(pc - po) / area;
                        let w1 = (pc - po).perp_dot(pa - po) / area;
                        let w2 = 1.0 - w0 - w1;
                        if w0 >= 0.0 && w1 >= 0.0 && w2 >= 0.0 {
                            let z = (a * w0 + b * w1 + c * w2).dot(m.view.d);
                            best = best.max(z);
                        }
                    }
                    if best.is_finite() {
                        worst = worst.max((best - p.dot(m.view.d)).abs());
                        n += 1;
                    }
                }
            }
        }
        println!("checked {n} pixels: worst |front depth - ray cast| = {:.3} mm", worst * 1e3);
    }
}
