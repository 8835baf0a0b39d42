//! The embedded parametric mannequin (MakeHuman hm08) and size-chart fitting.

pub mod data;
pub mod model;
pub mod size_chart;
pub mod landmarks;
