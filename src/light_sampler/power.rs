//! Lights chosen in proportion to their luminous power (lm), through an alias table: O(1) per
//! sample. pbrt-v4 weighs by radiometric power over visible wavelengths; luminous power is the
//! same idea weighted by what the eye (and the photometric image) sees.

use crate::light::{LightId, LightKind, LightTable};
use crate::sampling::AliasTable;

/// Power-proportional choice. Zero-power lights are never chosen.
#[derive(Clone, Debug, Default)]
pub struct PowerSampler {
    ids: Vec<LightId>,
    alias: AliasTable,
    /// `LightTable::kind_offsets` when built: maps a light to its alias-table index.
    offsets: [u32; LightKind::COUNT],
    generation: u64,
}

impl PowerSampler {
    /// Over the lights of `table`.
    pub fn build(table: &LightTable) -> Self {
        let ids: Vec<LightId> = table.ids().collect();
        let weights: Vec<f32> = ids.iter().map(|&id| table.luminous_power(id)).collect();
        Self { alias: AliasTable::new(&weights), ids, offsets: table.kind_offsets(), generation: table.generation }
    }

    /// Rebuilds the alias table when powers changed (lights added, removed, or re-powered); a
    /// table where lights only moved keeps its alias table.
    pub fn update(&mut self, table: &LightTable) -> &'static str {
        if self.generation == table.generation {
            return "up to date";
        }
        if !table.powers_changed && self.ids.len() == table.len() {
            self.generation = table.generation;
            return "lights moved, powers unchanged: alias table kept";
        }
        *self = Self::build(table);
        "powers changed: alias table rebuilt"
    }

    /// A light and its probability.
    #[inline]
    pub fn sample(&self, u: f32) -> Option<(LightId, f32)> {
        self.alias.sample(u).map(|(i, pmf)| (self.ids[i], pmf))
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
        self.ids.iter().enumerate().for_each(|(i, &id)| f(id, self.alias.pmf(i)));
    }

    /// Probability of choosing `light`.
    pub fn pmf(&self, light: LightId) -> f32 {
        let i = (self.offsets[light.kind.index()] + light.row) as usize;
        if self.ids.get(i) == Some(&light) { self.alias.pmf(i) } else { 0.0 }
    }
}
