//! Refinement benchmarks (issue #4): the straight skirt on the reference
//! body refined to 1, 2 and 3 levels (split + Butterfly + fairing), and 3
//! levels with depth-map collision avoidance and the exact final pass, and
//! building the body's winding-number hierarchy (cached per body). Run: `cargo bench --bench refine`.
#![expect(missing_docs, reason = "criterion_group! generates undocumented items")]

use criterion::{criterion_group, criterion_main, Criterion};
use grade3d::collide::render::{GpuContext, RenderOptions};
use grade3d::geom::winding::{WindingOptions, WindingTree};
use grade3d::refine::collision::{Collider, CollisionOptions};
use grade3d::refine::subdivide::{refine, RefineMesh, RefineOptions};
use grade3d::template::codec::decode;
use grade3d::template::format::Relocation;
use grade3d::template::library::{builtin, reference_body};

fn benches(c: &mut Criterion) {
    let body = reference_body().expect("reference body");
    let t = builtin().expect("library").into_iter().next().expect("skirt");
    let m0 = decode(&t, &body, Relocation::Eq1Frame).expect("decode");
    let edges: Vec<(u32, u32)> = t.edges.iter().map(|e| (e.start, e.end)).collect();
    let coarse = RefineMesh::from_coarse(&m0, &edges).expect("coarse");
    let mut g = c.benchmark_group("refine_skirt");
    g.sample_size(10);
    for levels in 1..=3 {
        let opts = RefineOptions { levels, ..Default::default() };
        g.bench_function(format!("levels_{levels}"), |b| {
            b.iter(|| refine(coarse.clone(), &opts, |_, _| {}).expect("refine"))
        });
    }
    if let Ok(gpu) = GpuContext::new() {
        let maps = gpu.render(&body.mesh, &RenderOptions::default()).expect("render");
        let tree = WindingTree::new(&body.mesh, &WindingOptions::default());
        let opts = RefineOptions::default();
        g.bench_function("levels_3_with_collision", |b| {
            b.iter(|| {
                let mut collider = Collider::new(&maps, CollisionOptions::default());
                let mut fine = refine(coarse.clone(), &opts, |p, h| collider.after_sweep(p, h)).expect("refine").mesh;
                collider.settle(&tree, &mut fine.positions, &fine.fixed);
                fine
            })
        });
        g.bench_function("winding_tree_of_the_body", |b| {
            b.iter(|| WindingTree::new(&body.mesh, &WindingOptions::default()))
        });
    }
    g.finish();
}

criterion_group!(refine_benches, benches);
criterion_main!(refine_benches);
