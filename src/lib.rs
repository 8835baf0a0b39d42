//! grade3d — automated 3D garment grading.
//!
//! The workspace's top (issue #16): the `grade3d` binary's library, which
//! names every layer under one roof so that tests, benches and examples
//! keep their paths — the pure core's modules ([`grade3d_core`]: `geom`,
//! `body`, `mannequin`, `template`, `refine`, `pattern`, `pipeline`), the
//! input parsers ([`io`], `grade3d-io`), collision with the wgpu renderer
//! ([`collide`], `grade3d-render` behind the core's `DepthRenderer`), the
//! HTTP service ([`service`], `grade3d-service`). The data generators are
//! the `xtask` crate (`cargo xtask data …`). Data flow and module map:
//! `ARCHITECTURE.md`.

pub use grade3d_core::{body, geom, mannequin, pattern, pipeline, refine, scan, template};
pub use grade3d_io as io;
pub use grade3d_service as service;
pub use grade3d_service::collide;
