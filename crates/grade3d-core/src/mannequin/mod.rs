//! The embedded parametric mannequin (MakeHuman hm08) and size-chart fitting.

pub mod data;
pub mod fit;
pub mod fixtures;
pub mod landmarks;
pub mod model;
pub mod population;
pub mod register;
pub mod size_chart;
