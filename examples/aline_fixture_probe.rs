//! Development probe (issue #18): the A-line skirt authored from its
//! fixture surface as `tests/from_garment.rs` authors it (no drafted
//! darts), its block decided on the reference body, and graded on the
//! fixture bodies and ASTM sizes whose name contains the filter, printing
//! the surface clearing's report and the hanging nodes nearest the body.
//!
//! `cargo run --release --example aline_fixture_probe -- size-12`

use grade3d::body::derive::{derive_features, DeriveOptions};
use grade3d::collide::cache::Obstacle;
use grade3d::collide::render::{RenderOptions, Renderer, RendererChoice};
use grade3d::collide::DepthRenderer;
use grade3d::geom::query::SphereIndex;
use grade3d::geom::winding::{WindingOptions, WindingTree};
use grade3d::io::obj::read_obj_panels;
use grade3d::pattern::garment::DartSource;
use grade3d::pipeline::{block, grade_with_darts, GradeOptions};
use grade3d::template::codec::decode;
use grade3d::template::from_garment::author_from_garment;

#[path = "../tests/common/mod.rs"]
mod common;

fn main() {
    let filter = std::env::args().nth(1).unwrap_or_else(|| "size-12".into());
    let renderer = Renderer::new(RendererChoice::Auto).unwrap();
    let obstacle = |mesh: &grade3d::geom::mesh::TriMesh| Obstacle {
        maps: renderer.depth_maps(mesh, &RenderOptions::default()).unwrap(),
        tree: WindingTree::new(mesh, &WindingOptions::default()),
    };
    let body = grade3d::template::library::reference_body().unwrap();
    let read = read_obj_panels(&std::fs::read_to_string("fixtures/garments/a-line-skirt.obj").unwrap()).unwrap();
    let a = author_from_garment("a-line-skirt", &read, &body, &grade3d::template::drawn::garment_options()).unwrap();
    let t = a.template;
    let plan = block(&t, &body, Some(&obstacle(&body.mesh)), &GradeOptions::default()).unwrap();
    for (n, mesh, lm) in common::fixture_bodies().into_iter().filter(|(n, ..)| n.contains(filter.as_str())) {
        {
            let fb = derive_features(mesh, &lm, &DeriveOptions::default()).unwrap();
            let o = obstacle(&fb.mesh);
            // the gap between the left arm and the trunk, per level (mm)
            for y_mm in [100, 140, 170, 200, 230] {
                let plane = grade3d::geom::plane::Plane { normal: glam::DVec3::Y, offset: y_mm as f64 * 1e-3 };
                let loops: Vec<_> = grade3d::geom::slice::slice(&fb.mesh, &plane)
                    .into_iter()
                    .map(|s| s.polyline)
                    .filter(|l| l.closed)
                    .collect();
                let cx = |l: &grade3d::geom::polyline::Polyline| l.centroid().x;
                let trunk = loops.iter().min_by(|a, b| cx(a).abs().total_cmp(&cx(b).abs()));
                let arm = loops.iter().filter(|l| cx(l) > 0.05).max_by(|a, b| cx(a).total_cmp(&cx(b)));
                let gap = match (trunk, arm) {
                    (Some(t), Some(a)) if !std::ptr::eq(t, a) => a
                        .points
                        .iter()
                        .filter_map(|&p| t.closest(p).map(|c| c.point.distance(p)))
                        .fold(f64::MAX, f64::min),
                    _ => f64::NAN,
                };
                println!("  y {y_mm} mm: {} loops, left arm to trunk {:.1} mm", loops.len(), gap * 1e3);
            }
            let g =
                grade_with_darts(&t, &fb, Some(&o), &n, &GradeOptions::default(), DartSource::Block(&plan)).unwrap();
            println!("{n}: {:?}", g.collision.surface);
            let pairs = grade3d::geom::intersect::intersecting_pairs(&o.tree, &g.mesh.positions, &g.mesh.triangles);
            for pr in pairs.iter().take(30) {
                let t3 = g.mesh.triangles[pr.garment];
                let c = t3.iter().map(|&v| g.mesh.positions[v]).sum::<glam::DVec3>() / 3.0 * 1e3;
                println!("  through at [{:.0}, {:.0}, {:.0}] mm", c.x, c.y, c.z);
            }
            let m = decode(&t, &fb, t.defaults.relocation).unwrap();
            let index = SphereIndex::new(&fb.mesh);
            let mut near: Vec<(f64, u32)> = t
                .below
                .iter()
                .map(|b| {
                    let p = m.positions[b.node as usize];
                    let d = index.closest_point(&fb.mesh, p).point.distance(p) * 1e3;
                    (if o.tree.is_inside(p) { -d } else { d }, b.node)
                })
                .collect();
            near.sort_by(|a, b| a.0.total_cmp(&b.0));
            println!("  nearest hanging nodes (mm, node): {:?}", &near[..6.min(near.len())]);
        }
    }
}
