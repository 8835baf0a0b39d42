//! Collision avoidance during refinement (seed 000 §5.4).
//!
//! After every fairing sweep ([`super::subdivide::refine`]'s hook), each
//! free vertex is tested against the body's depth maps by Eq. (13), with
//! the body thickened by [`CollisionOptions::detection_margin_mm`]
//! ([`crate::collide::depth::inside_with_margin`]):
//! * a vertex the sweep moved from outside to inside has its update
//!   **refused** — sub-stepped as the paper suggests: of the fractions
//!   `k/n` (`n` = [`CollisionOptions::substeps`]) of its update, the largest
//!   that stays outside is kept (0 if none);
//! * a vertex that is inside for any other reason (a new vertex of the
//!   split, a vertex inside since the start of the level) is **pushed out**
//!   along the body normal at the nearer depth-map face by its escape
//!   distance plus the clearance [`CollisionOptions::clearance_mm`].
//!
//! Fixed vertices (nodes, profile and boundary vertices) are never moved.
//! No failure modes: points outside every map are outside.

use glam::DVec3;
use serde::{Deserialize, Serialize};

use crate::collide::depth::{inside_with_margin, DepthMap};

/// Knobs of collision avoidance.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct CollisionOptions {
    /// Distance a pushed-out vertex is placed outside the body, mm. Default 3.
    pub clearance_mm: f64,
    /// Sub-steps tried when a fairing update would enter the body. Default 4.
    pub substeps: u32,
    /// The body is thickened by this much along each view axis when
    /// testing, so that vertices a pixel's width from the skin — where the
    /// depth maps cannot resolve in from out — count as inside, mm.
    /// Default 1.5.
    pub detection_margin_mm: f64,
}

impl Default for CollisionOptions {
    fn default() -> Self {
        Self { clearance_mm: 3.0, substeps: 4, detection_margin_mm: 1.5 }
    }
}

/// What the collision step did over a refinement.
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize)]
pub struct CollisionReport {
    /// Vertices pushed out of the body.
    pub pushed: usize,
    /// Fairing updates refused (wholly or partly).
    pub refused: usize,
}

/// The hook state: the depth maps and the positions after the last sweep.
pub struct Collider<'a> {
    maps: &'a [DepthMap],
    opts: CollisionOptions,
    previous: Vec<DVec3>,
    /// Running totals.
    pub report: CollisionReport,
}

impl<'a> Collider<'a> {
    /// A collider over the depth maps of one body.
    pub fn new(maps: &'a [DepthMap], opts: CollisionOptions) -> Self {
        Self { maps, opts, previous: Vec::new(), report: CollisionReport::default() }
    }

    /// The hook: refuse updates that enter the body, push out what is inside.
    pub fn after_sweep(&mut self, positions: &mut [DVec3], fixed: &[bool]) {
        let clearance = self.opts.clearance_mm * 1e-3;
        let margin = self.opts.detection_margin_mm * 1e-3;
        let maps = self.maps;
        let hit = |q: DVec3| inside_with_margin(maps, q, margin);
        let same_level = self.previous.len() == positions.len();
        for (i, p) in positions.iter_mut().enumerate() {
            if fixed.get(i).copied().unwrap_or(true) {
                continue;
            }
            let Some(probe) = hit(*p) else { continue };
            if same_level && hit(self.previous[i]).is_none() {
                let from = self.previous[i];
                let n = self.opts.substeps.max(1);
                let mut kept = from;
                for k in (1..n).rev() {
                    let q = from.lerp(*p, f64::from(k) / f64::from(n));
                    if hit(q).is_none() {
                        kept = q;
                        break;
                    }
                }
                *p = kept;
                self.report.refused += 1;
            } else {
                *p += probe.normal * (probe.escape - margin + clearance);
                self.report.pushed += 1;
            }
        }
        self.previous.clear();
        self.previous.extend_from_slice(positions);
    }
}
