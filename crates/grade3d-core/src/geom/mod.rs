//! Geometry kernel: meshes, planes, polylines, plane sections, proximity
//! queries, simplification and Coons patches. Pure functions on plain data.

pub mod coons;
pub mod cut;
pub mod flip;
pub mod intersect;
pub mod mesh;
pub mod plane;
pub mod polyline;
pub mod query;
pub mod repair;
pub mod simplify;
pub mod slice;
pub mod topology;
pub mod winding;
