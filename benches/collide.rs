//! Collision benchmarks (issue #4): depth-map render and read-back at
//! 512² and 1024² (GL/llvmpipe and Vulkan/lavapipe, and the core's CPU
//! rasteriser), and the depth-map
//! inside test per point against the exact (winding-number) test.
//! Run: `cargo bench --bench collide`.
#![expect(missing_docs, reason = "criterion_group! generates undocumented items")]

use std::path::Path;

use criterion::{criterion_group, criterion_main, Criterion};
use glam::DVec3;
use grade3d::collide::depth::inside;
use grade3d::collide::raster::CpuRasteriser;
use grade3d::collide::render::{GpuContext, RenderOptions};
use grade3d::collide::DepthRenderer;
use grade3d::geom::winding::{WindingOptions, WindingTree};
use grade3d::io::gltf::read_mesh;

fn benches(c: &mut Criterion) {
    let mesh = read_mesh(
        &std::fs::read(Path::new(env!("CARGO_MANIFEST_DIR")).join("fixtures/bodies/female-average-caucasian.glb"))
            .expect("glb"),
        &Default::default(),
    )
    .expect("mesh");
    let mut g = c.benchmark_group("depth_maps");
    g.sample_size(10);
    for (backends, label) in [(wgpu::Backends::GL, "gl"), (wgpu::Backends::VULKAN, "vulkan")] {
        let Ok(gpu) = GpuContext::with_backends(backends) else {
            eprintln!("no {label} adapter; skipped");
            continue;
        };
        for res in [512u32, 1024] {
            let opts = RenderOptions { resolution: res, ..Default::default() };
            g.bench_function(format!("render_readback_{label}_{res}"), |b| {
                b.iter(|| gpu.render(&mesh, &opts).expect("render"))
            });
        }
    }
    // the core's CPU rasteriser, the renderer where the adapter is a CPU driver (issue #15)
    for res in [512u32, 1024] {
        let opts = RenderOptions { resolution: res, ..Default::default() };
        g.bench_function(format!("render_cpu_rasteriser_{res}"), |b| {
            b.iter(|| CpuRasteriser.depth_maps(&mesh, &opts).expect("render"))
        });
    }
    g.finish();

    if let Ok(gpu) = GpuContext::new() {
        let maps = gpu.render(&mesh, &RenderOptions::default()).expect("render");
        let bb = mesh.aabb();
        let pts: Vec<DVec3> = (0..10_000)
            .map(|i| {
                let f = |k: u64| ((i as u64 * 2_654_435_761 + k * 40_503) % 10_007) as f64 / 10_007.0;
                bb.min + (bb.max - bb.min) * DVec3::new(f(1), f(2), f(3))
            })
            .collect();
        c.bench_function("inside_depth_map_10k_points", |b| {
            b.iter(|| pts.iter().filter(|p| inside(&maps, **p).is_some()).count())
        });
        let tree = WindingTree::new(&mesh, &WindingOptions::default());
        c.bench_function("inside_exact_winding_10k_points", |b| {
            b.iter(|| pts.iter().filter(|p| tree.is_inside(**p)).count())
        });
    }
}

criterion_group!(collide, benches);
criterion_main!(collide);
