//! Every light equally likely.

use crate::light::{LightId, LightTable};

/// Uniform choice over the table's lights.
#[derive(Clone, Debug, Default)]
pub struct UniformSampler {
    ids: Vec<LightId>,
    generation: u64,
}

impl UniformSampler {
    /// Over the lights of `table`.
    pub fn build(table: &LightTable) -> Self {
        Self { ids: table.ids().collect(), generation: table.generation }
    }

    /// Refreshes the id list if the table changed.
    pub fn update(&mut self, table: &LightTable) -> &'static str {
        if self.generation == table.generation {
            return "up to date";
        }
        self.ids.clear();
        self.ids.extend(table.ids());
        self.generation = table.generation;
        "id list refreshed"
    }

    /// A light and its pmf 1/n.
    #[inline]
    pub fn sample(&self, u: f32) -> Option<(LightId, f32)> {
        let n = self.ids.len();
        if n == 0 {
            return None;
        }
        let i = ((u * n as f32) as usize).min(n - 1);
        Some((self.ids[i], 1.0 / n as f32))
    }

    /// Number of lights.
    pub fn len(&self) -> usize {
        self.ids.len()
    }

    /// True with no lights.
    pub fn is_empty(&self) -> bool {
        self.ids.is_empty()
    }

    /// Calls `f` with every light and its pmf.
    pub fn for_each_pmf(&self, mut f: impl FnMut(LightId, f32)) {
        let pmf = self.pmf(LightId { kind: crate::light::LightKind::Point, row: 0 });
        self.ids.iter().for_each(|&id| f(id, pmf));
    }

    /// 1/n for any light of the table.
    pub fn pmf(&self, _light: LightId) -> f32 {
        if self.ids.is_empty() { 0.0 } else { 1.0 / self.ids.len() as f32 }
    }
}
