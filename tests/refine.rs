//! Refinement with collision avoidance on real bodies (issue #4): every
//! library template on every fixture body and ASTM size mannequin, three
//! levels; penetration judged by the exact (winding-number) inside test;
//! agreement of the depth-map inside test with the exact one.

use glam::DVec3;
use grade3d::body::derive::{derive_features, DeriveOptions};
use grade3d::collide::depth::{inside, ViewSet};
use grade3d::collide::render::{RenderOptions, Renderer, RendererChoice};
use grade3d::collide::DepthRenderer;
use grade3d::geom::winding::{penetration_stats, WindingOptions, WindingTree};
use grade3d::refine::collision::{Collider, CollisionOptions};
use grade3d::refine::subdivide::{refine, RefineMesh, RefineOptions, Refined};
use grade3d::template::codec::decode;
use grade3d::template::format::Relocation;
use grade3d::template::library::builtin;

mod common;
use common::fixture_bodies;

#[test]
fn library_on_every_body_stays_outside() {
    let renderer = Renderer::new(RendererChoice::Auto).expect("a depth-map renderer (the one the service picks)");
    let library = builtin().unwrap();
    let mut worst_on = (0.0f64, String::new());
    let mut worst_off = (0.0f64, String::new());
    let (mut inside_on, mut inside_off, mut total) = (0usize, 0usize, 0usize);
    let mut last_reports = None;
    let (mut inside_maps, mut worst_maps, mut settled, mut held) = (0usize, (0.0f64, String::new()), 0usize, 0usize);
    let (mut max_iterations, mut worst_update) = (0usize, 0.0f64);
    for (name, mesh, lm) in fixture_bodies() {
        let body = derive_features(mesh, &lm, &DeriveOptions::default()).unwrap();
        let maps = renderer.depth_maps(&body.mesh, &RenderOptions::default()).unwrap();
        let tree = WindingTree::new(&body.mesh, &WindingOptions::default());
        for t in &library {
            let m0 = decode(t, &body, Relocation::Eq1Frame).unwrap();
            let edges: Vec<(u32, u32)> = t.edges.iter().map(|e| (e.start, e.end)).collect();
            let opts = RefineOptions::default();
            let mut collider = Collider::new(&maps, CollisionOptions::default());
            let Refined { mesh: mut on, levels: reports, .. } =
                refine(RefineMesh::from_coarse(&m0, &edges).unwrap(), &opts, |p, f| collider.after_sweep(p, f))
                    .unwrap();
            assert!(
                reports.iter().all(|r| r.converged),
                "{} on {name}: fairing with collision did not converge: {reports:?}",
                t.name
            );
            max_iterations = max_iterations.max(reports.iter().map(|r| r.fairing_sweeps).max().unwrap_or(0));
            worst_update = worst_update.max(reports.iter().map(|r| r.final_update_rel).fold(0.0, f64::max));
            held += reports.iter().map(|r| r.held).sum::<usize>();
            assert_eq!(on.triangles.len(), m0.triangles.len() * 64, "{}: 3 levels multiply faces by 4^3", t.name);
            let Refined { mesh: off, levels: free_reports, .. } =
                refine(RefineMesh::from_coarse(&m0, &edges).unwrap(), &opts, |_, _| {}).unwrap();
            assert!(
                free_reports.iter().all(|r| r.converged),
                "{} on {name}: fairing did not converge: {free_reports:?}",
                t.name
            );
            last_reports = Some((format!("{} on {name}", t.name), reports, collider.report));
            // free vertices only: nodes and profile vertices are the template's own placement
            let free = |m: &RefineMesh| -> Vec<DVec3> {
                m.positions.iter().zip(&m.fixed).filter(|(_, f)| !**f).map(|(p, _)| *p).collect()
            };
            let s_maps = penetration_stats(&tree, &free(&on));
            inside_maps += s_maps.inside;
            if s_maps.deepest_m > worst_maps.0 {
                worst_maps = (s_maps.deepest_m, format!("{} on {name}", t.name));
            }
            collider.settle(&tree, &mut on.positions, &on.fixed);
            settled += collider.report.settled;
            let s_on = penetration_stats(&tree, &free(&on));
            let s_off = penetration_stats(&tree, &free(&off));
            total += s_on.total;
            inside_on += s_on.inside;
            inside_off += s_off.inside;
            if s_on.deepest_m > worst_on.0 {
                worst_on = (s_on.deepest_m, format!("{} on {name}", t.name));
            }
            if s_off.deepest_m > worst_off.0 {
                worst_off = (s_off.deepest_m, format!("{} on {name}", t.name));
            }
            assert!(
                s_on.deepest_m <= 1e-3,
                "{} on {name}: a free vertex is {:.2} mm inside the body ({} of {} inside)",
                t.name,
                s_on.deepest_m * 1e3,
                s_on.inside,
                s_on.total
            );
        }
    }
    eprintln!("last run with collision: {last_reports:?}");
    eprintln!(
        "fairing with collision: every level converged; most iterations in a level {max_iterations}, \
         largest final update {worst_update:.2e} of the diagonal; {held} vertices held in all"
    );
    eprintln!(
        "depth maps only (before the exact pass): {inside_maps} of {total} free vertices inside, deepest {:.2} mm ({}); \
         the exact pass moved {settled}",
        worst_maps.0 * 1e3,
        worst_maps.1
    );
    eprintln!(
        "with collision avoidance: {inside_on} of {total} free vertices inside, deepest {:.2} mm ({}); \
         without: {inside_off} inside, deepest {:.2} mm ({})",
        worst_on.0 * 1e3,
        worst_on.1,
        worst_off.0 * 1e3,
        worst_off.1
    );
}

#[test]
fn depth_map_inside_test_agrees_with_the_exact_test() {
    let renderer = Renderer::new(RendererChoice::Auto).expect("a depth-map renderer (the one the service picks)");
    let (_, mesh, _) = fixture_bodies().swap_remove(1);
    let tree = WindingTree::new(&mesh, &WindingOptions::default());
    let bb = mesh.aabb();
    let n = 1_000_000u64;
    // deterministic quasi-random points (additive recurrence, R3 sequence)
    let g = 1.220_744_084_605_759_5f64;
    let a = [1.0 / g, 1.0 / (g * g), 1.0 / (g * g * g)];
    let points: Vec<DVec3> = (1..=n)
        .map(|i| {
            let f = |k: usize| (0.5 + a[k] * i as f64).fract();
            bb.min + (bb.max - bb.min) * DVec3::new(f(0), f(1), f(2))
        })
        .collect();
    let exact: Vec<bool> = points.iter().map(|p| tree.is_inside(*p)).collect();
    for (views, resolution) in [
        (ViewSet::FrontBack, 512),
        (ViewSet::FrontBackSides, 512),
        (ViewSet::FrontBack, 1024),
        (ViewSet::FrontBackSides, 1024),
    ] {
        let maps = renderer.depth_maps(&mesh, &RenderOptions { views, resolution, ..Default::default() }).unwrap();
        let mut disagree = 0usize;
        let mut near_surface = 0usize;
        let mut false_inside = 0usize;
        for (p, &e) in points.iter().zip(&exact) {
            let d = inside(&maps, *p).is_some();
            if d != e {
                disagree += 1;
                if d {
                    false_inside += 1;
                }
                if tree.signed_depth(*p).abs() < 5e-3 {
                    near_surface += 1;
                }
            }
        }
        let agreement = 1.0 - disagree as f64 / n as f64;
        eprintln!(
            "{views:?} at {resolution}²: agreement {:.4} % on {n} points; {disagree} disagree ({false_inside} read inside, \
             {near_surface} within 5 mm of the surface)",
            100.0 * agreement
        );
        if views == ViewSet::FrontBackSides && resolution == 1024 {
            assert!(agreement >= 0.999, "agreement {agreement}");
        }
    }
}
