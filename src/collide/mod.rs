//! Collision avoidance against the body (seed 000 §5.4): depth maps
//! rendered offscreen with wgpu ([`render`], the only GPU module) and the
//! image-based inside test of Eq. (13) ([`depth`]), cached per body ([`cache`]).

pub mod cache;
pub mod depth;
pub mod render;
