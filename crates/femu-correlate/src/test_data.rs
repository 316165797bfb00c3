//! What every test reader returns (CSV, JSON, a Universal File's datasets 15/2411 and 55):
//! the sensors, the modes, and the test nodes' coordinates where the file gives them.

use crate::{Sensor, TestModes};
use std::collections::BTreeMap;

/// Test modes and the sensors they were measured with.
#[derive(Debug, Clone)]
pub struct TestData {
    /// The sensors, in the order of the shape rows.
    pub sensors: Vec<Sensor>,
    /// The modes.
    pub modes: TestModes,
    /// Test node coordinates the file gives (its own frame and units; empty when it gives none).
    pub coordinates: BTreeMap<u64, [f64; 3]>,
}
