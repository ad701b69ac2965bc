//! Charts of a recording's totals.

use super::reader::Recording;
use std::path::Path;

/// Draws energy, momentum and collisions over the steps to `path` (.svg or .png).
pub fn totals_chart(_rec: &Recording, path: &Path) -> anyhow::Result<()> {
    anyhow::bail!("plotting to {} is not built yet", path.display())
}
