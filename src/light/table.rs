//! `LightTable`: every light of the world, resolved to world space, one block per kind. Point
//! and spot lights are structure-of-arrays columns (the hot batch paths read them); the other
//! kinds are rows of their resolved form. Rows stay dense: removal swap-removes and fixes the
//! entity -> rows map.

use std::collections::HashMap;

use bevy_ecs::entity::Entity;
use bevy_ecs::resource::Resource;

use super::{LightKind, ResolvedDistant, point::PointColumns, spot::SpotColumns};

/// A light: its kind and its row in that kind's block. Rows move when lights are removed, so a
/// `LightId` is valid until the next table update.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct LightId {
    pub kind: LightKind,
    pub row: u32,
}

/// Rows of a resolved light type with the entity that owns each row.
#[derive(Clone, Debug)]
pub struct Rows<T> {
    pub items: Vec<T>,
    pub owner: Vec<Entity>,
    /// Whether shadow rays are traced for the row's light.
    pub casts_shadows: Vec<bool>,
}

impl<T> Default for Rows<T> {
    fn default() -> Self {
        Self { items: Vec::new(), owner: Vec::new(), casts_shadows: Vec::new() }
    }
}

/// Operations every block supports, so the table's bookkeeping is written once.
pub trait Block {
    type Row;
    fn len(&self) -> usize;
    fn push(&mut self, owner: Entity, row: Self::Row, casts_shadows: bool);
    fn set(&mut self, i: usize, row: Self::Row, casts_shadows: bool);
    /// Removes row `i` by moving the last row into it.
    fn swap_remove(&mut self, i: usize);
    fn owner(&self, i: usize) -> Entity;
}

impl<T> Block for Rows<T> {
    type Row = T;
    fn len(&self) -> usize {
        self.items.len()
    }
    fn push(&mut self, owner: Entity, row: T, casts_shadows: bool) {
        self.items.push(row);
        self.owner.push(owner);
        self.casts_shadows.push(casts_shadows);
    }
    fn set(&mut self, i: usize, row: T, casts_shadows: bool) {
        self.items[i] = row;
        self.casts_shadows[i] = casts_shadows;
    }
    fn swap_remove(&mut self, i: usize) {
        self.items.swap_remove(i);
        self.owner.swap_remove(i);
        self.casts_shadows.swap_remove(i);
    }
    fn owner(&self, i: usize) -> Entity {
        self.owner[i]
    }
}

/// All lights, by kind. Invariant: `rows_of` maps each light entity to exactly the rows whose
/// `owner` is that entity, and every row has an entry.
#[derive(Resource, Clone, Debug, Default)]
pub struct LightTable {
    pub points: PointColumns,
    pub spots: SpotColumns,
    pub distant: Rows<ResolvedDistant>,
    rows_of: HashMap<Entity, Vec<LightId>>,
    /// Bumped on every change; samplers compare it to know when to update.
    pub generation: u64,
    /// Set when a light was added, removed or changed its power since the flags were cleared.
    pub powers_changed: bool,
    /// Set when a light moved (same power) since the flags were cleared.
    pub moved: bool,
    /// Rows set in place (moved or re-powered) since the flags were cleared, in order, possibly
    /// repeated: what an incremental sampler refits.
    pub changed_rows: Vec<LightId>,
    /// Set when rows were added or removed since the flags were cleared (rows may have moved).
    pub rows_reordered: bool,
    /// `generation` when the flags were last cleared: the flags describe every change after it.
    pub changes_since: u64,
}

macro_rules! for_block {
    ($table:expr, $kind:expr, |$b:ident| $body:expr) => {
        match $kind {
            LightKind::Point => {
                let $b = &mut $table.points;
                $body
            }
            LightKind::Spot => {
                let $b = &mut $table.spots;
                $body
            }
            LightKind::Distant => {
                let $b = &mut $table.distant;
                $body
            }
            other => unreachable!("no block for {other:?}"),
        }
    };
}

impl LightTable {
    /// Number of lights (rows) of every kind.
    pub fn len(&self) -> usize {
        self.points.len() + self.spots.len() + self.distant.len()
    }
    /// True with no lights.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }
    /// Rows owned by `entity`.
    pub fn rows_of(&self, entity: Entity) -> &[LightId] {
        self.rows_of.get(&entity).map_or(&[], Vec::as_slice)
    }
    /// Number of light entities.
    pub fn entity_count(&self) -> usize {
        self.rows_of.len()
    }
    /// Every light id, kind by kind.
    pub fn ids(&self) -> impl Iterator<Item = LightId> + '_ {
        let block = |kind, n: usize| (0..n as u32).map(move |row| LightId { kind, row });
        block(LightKind::Point, self.points.len())
            .chain(block(LightKind::Spot, self.spots.len()))
            .chain(block(LightKind::Distant, self.distant.len()))
    }
    /// The entity that owns light `id`.
    pub fn owner(&self, id: LightId) -> Entity {
        let i = id.row as usize;
        match id.kind {
            LightKind::Point => self.points.owner(i),
            LightKind::Spot => self.spots.owner(i),
            LightKind::Distant => self.distant.owner(i),
            other => unreachable!("no block for {other:?}"),
        }
    }

    /// Inserts or replaces the single light row of `entity` in block `kind`: in place when the
    /// entity already has exactly that row (a moving light), else after removing its old rows.
    pub fn upsert_point(
        &mut self,
        entity: Entity,
        row: super::ResolvedPoint,
        casts_shadows: bool,
        power_changed: bool,
    ) {
        self.upsert(entity, LightKind::Point, power_changed, |t| &mut t.points, row, casts_shadows);
    }
    /// See [`Self::upsert_point`].
    pub fn upsert_spot(&mut self, entity: Entity, row: super::ResolvedSpot, casts_shadows: bool, power_changed: bool) {
        self.upsert(entity, LightKind::Spot, power_changed, |t| &mut t.spots, row, casts_shadows);
    }
    /// See [`Self::upsert_point`].
    pub fn upsert_distant(&mut self, entity: Entity, row: ResolvedDistant, casts_shadows: bool, power_changed: bool) {
        self.upsert(entity, LightKind::Distant, power_changed, |t| &mut t.distant, row, casts_shadows);
    }

    fn upsert<B: Block>(
        &mut self,
        entity: Entity,
        kind: LightKind,
        power_changed: bool,
        block: impl Fn(&mut Self) -> &mut B,
        row: B::Row,
        casts_shadows: bool,
    ) {
        self.generation += 1;
        if let Some(&[id]) = self.rows_of.get(&entity).map(Vec::as_slice)
            && id.kind == kind
        {
            block(self).set(id.row as usize, row, casts_shadows);
            self.changed_rows.push(id);
            self.moved = true;
            self.powers_changed |= power_changed;
            return;
        }
        self.remove(entity);
        let b = block(self);
        let i = b.len() as u32;
        b.push(entity, row, casts_shadows);
        self.rows_of.insert(entity, vec![LightId { kind, row: i }]);
        self.powers_changed = true;
        self.rows_reordered = true;
    }

    /// Removes every row of `entity`, keeping blocks dense. Returns how many rows went.
    pub fn remove(&mut self, entity: Entity) -> usize {
        let Some(mut ids) = self.rows_of.remove(&entity) else { return 0 };
        // Highest rows first, so a row moved into a hole is never one still to be removed.
        ids.sort_by(|a, b| b.cmp(a));
        for id in &ids {
            let i = id.row as usize;
            let moved_from = for_block!(self, id.kind, |b| {
                let last = b.len() - 1;
                b.swap_remove(i);
                (i != last).then(|| (b.owner(i), last))
            });
            if let Some((moved_owner, last)) = moved_from
                && let Some(rows) = self.rows_of.get_mut(&moved_owner)
            {
                for r in rows.iter_mut().filter(|r| r.kind == id.kind && r.row as usize == last) {
                    r.row = id.row;
                }
            }
        }
        self.generation += 1;
        self.powers_changed = true;
        self.rows_reordered = true;
        ids.len()
    }

    /// Clears the change flags (after samplers have caught up).
    pub fn clear_change_flags(&mut self) {
        self.powers_changed = false;
        self.moved = false;
        self.changed_rows.clear();
        self.rows_reordered = false;
        self.changes_since = self.generation;
    }
}
