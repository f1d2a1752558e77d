//! `LightTable`: every light of the world, resolved to world space, one block per kind. Point
//! and spot lights are structure-of-arrays columns (the hot batch paths read them); the other
//! kinds are rows of their resolved form. Rows stay dense: removal swap-removes and fixes the
//! entity -> rows map.

use bevy_ecs::entity::{Entity, EntityHashMap};
use bevy_ecs::resource::Resource;

use super::{
    LightKind, ResolvedArea, ResolvedDistant, ResolvedGoniometric, ResolvedImageInfinite, ResolvedProjection,
    ResolvedSunSky, ResolvedUniformInfinite, point::PointColumns, spot::SpotColumns,
};

/// A light: its kind and its row in that kind's block. Rows move when lights are removed, so a
/// `LightId` is valid until the next table update.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct LightId {
    /// Which block the light's row is in.
    pub kind: LightKind,
    /// The row within that block.
    pub row: u32,
}

/// Rows of a resolved light type with the entity that owns each row.
#[derive(Clone, Debug)]
pub struct Rows<T> {
    /// The resolved lights, one per row.
    pub items: Vec<T>,
    /// The entity each row belongs to.
    pub owner: Vec<Entity>,
    /// Whether shadow rays are traced for the row's light.
    pub casts_shadows: Vec<bool>,
}

impl<T> Default for Rows<T> {
    fn default() -> Self {
        Self { items: Vec::new(), owner: Vec::new(), casts_shadows: Vec::new() }
    }
}

/// One emitting shape of an area light: a sphere, disk or rectangle (primitive 0), or one
/// triangle of a mesh (its index in the mesh).
#[derive(Clone, Debug, PartialEq)]
pub struct AreaRow {
    /// The emitter (its radiance, spectrum, sides) of the row.
    pub light: ResolvedArea,
    /// The emitting triangle or shape of that emitter.
    pub primitive: u32,
}

/// Operations every block supports, so the table's bookkeeping is written once.
pub trait Block {
    /// What one row holds.
    type Row;
    /// Rows in the block.
    fn len(&self) -> usize;
    /// No rows.
    fn is_empty(&self) -> bool {
        self.len() == 0
    }
    /// Appends a row owned by `owner`.
    fn push(&mut self, owner: Entity, row: Self::Row, casts_shadows: bool);
    /// Replaces row `i` in place.
    fn set(&mut self, i: usize, row: Self::Row, casts_shadows: bool);
    /// Removes row `i` by moving the last row into it.
    fn swap_remove(&mut self, i: usize);
    /// The entity that owns row `i`.
    fn owner(&self, i: usize) -> Entity;
}

impl<T> Block for Rows<T> {
    type Row = T;
    /// Rows in the block.
    fn len(&self) -> usize {
        self.items.len()
    }
    /// Appends a row owned by `owner`.
    fn push(&mut self, owner: Entity, row: T, casts_shadows: bool) {
        self.items.push(row);
        self.owner.push(owner);
        self.casts_shadows.push(casts_shadows);
    }
    /// Replaces row `i` in place.
    fn set(&mut self, i: usize, row: T, casts_shadows: bool) {
        self.items[i] = row;
        self.casts_shadows[i] = casts_shadows;
    }
    fn swap_remove(&mut self, i: usize) {
        self.items.swap_remove(i);
        self.owner.swap_remove(i);
        self.casts_shadows.swap_remove(i);
    }
    /// The entity that owns row `i`.
    fn owner(&self, i: usize) -> Entity {
        self.owner[i]
    }
}

/// All lights, by kind. Invariant: `rows_of` maps each light entity to exactly the rows whose
/// `owner` is that entity, and every row has an entry.
#[derive(Resource, Clone, Debug, Default)]
pub struct LightTable {
    pub(crate) points: PointColumns,
    pub(crate) spots: SpotColumns,
    pub(crate) area: Rows<AreaRow>,
    pub(crate) projection: Rows<ResolvedProjection>,
    pub(crate) goniometric: Rows<ResolvedGoniometric>,
    pub(crate) distant: Rows<ResolvedDistant>,
    pub(crate) uniform_infinite: Rows<ResolvedUniformInfinite>,
    pub(crate) image_infinite: Rows<ResolvedImageInfinite>,
    pub(crate) sun_sky: Rows<ResolvedSunSky>,
    /// Image lights sample their MIS-compensated tables (valid only when the caller combines light
    /// samples with BSDF samples by MIS); set from `Settings::mis` by the sampling system.
    pub(crate) mis_compensation: bool,
    rows_of: EntityHashMap<Vec<LightId>>,
    /// Bumped on every change; samplers compare it to know when to update.
    pub(crate) generation: u64,
    /// Set when a light was added, removed or changed its power since the flags were cleared.
    pub(crate) powers_changed: bool,
    /// Set when a light moved (same power) since the flags were cleared.
    pub(crate) moved: bool,
    /// Rows set in place (moved or re-powered) since the flags were cleared, in order, possibly
    /// repeated: what an incremental sampler refits.
    pub(crate) changed_rows: Vec<LightId>,
    /// Set when rows were added or removed since the flags were cleared (rows may have moved).
    pub(crate) rows_reordered: bool,
    /// `generation` when the flags were last cleared: the flags describe every change after it.
    pub(crate) changes_since: u64,
}

/// Read access to the table: its blocks of rows by kind and its change log. The table is written
/// only by the light system's sync systems, which keep `rows_of` and the rows' owners in step.
impl LightTable {
    /// Point light rows.
    pub fn points(&self) -> &PointColumns {
        &self.points
    }
    /// Spot light rows.
    pub fn spots(&self) -> &SpotColumns {
        &self.spots
    }
    /// Area light rows: one per emitting triangle or analytic shape.
    pub fn area(&self) -> &Rows<AreaRow> {
        &self.area
    }
    /// Projection light rows.
    pub fn projection(&self) -> &Rows<ResolvedProjection> {
        &self.projection
    }
    /// Goniometric (IES and image-profile) light rows.
    pub fn goniometric(&self) -> &Rows<ResolvedGoniometric> {
        &self.goniometric
    }
    /// Distant light rows.
    pub fn distant(&self) -> &Rows<ResolvedDistant> {
        &self.distant
    }
    /// Uniform infinite light rows.
    pub fn uniform_infinite(&self) -> &Rows<ResolvedUniformInfinite> {
        &self.uniform_infinite
    }
    /// Image infinite light rows.
    pub fn image_infinite(&self) -> &Rows<ResolvedImageInfinite> {
        &self.image_infinite
    }
    /// Sun-and-sky rows.
    pub fn sun_sky(&self) -> &Rows<ResolvedSunSky> {
        &self.sun_sky
    }
    /// Whether image lights sample their MIS-compensated tables.
    pub fn mis_compensation(&self) -> bool {
        self.mis_compensation
    }
    /// Bumped on every change; samplers compare it to know when to update.
    pub fn generation(&self) -> u64 {
        self.generation
    }
    /// A light was added, removed or changed its power since the change log was cleared.
    pub fn powers_changed(&self) -> bool {
        self.powers_changed
    }
    /// A light moved (same power) since the change log was cleared.
    pub fn moved(&self) -> bool {
        self.moved
    }
    /// Rows set in place (moved or re-powered) since the change log was cleared, in order,
    /// possibly repeated.
    pub fn changed_rows(&self) -> &[LightId] {
        &self.changed_rows
    }
    /// Rows were added or removed since the change log was cleared (rows may have moved).
    pub fn rows_reordered(&self) -> bool {
        self.rows_reordered
    }
    /// `generation` when the change log was last cleared.
    pub fn changes_since(&self) -> u64 {
        self.changes_since
    }
}

/// Runs `$body` with `$b` bound to the block of `$kind` (`&mut` unless the table is given as
/// `ref table`): one exhaustive match, so a new kind is a compile error until it has a block.
macro_rules! for_block {
    (ref $table:expr, $kind:expr, |$b:ident| $body:expr) => {
        for_block!(@ $table, $kind, |$b| $body, &)
    };
    ($table:expr, $kind:expr, |$b:ident| $body:expr) => {
        for_block!(@ $table, $kind, |$b| $body, &mut)
    };
    (@ $table:expr, $kind:expr, |$b:ident| $body:expr, $($borrow:tt)+) => {
        match $kind {
            LightKind::Point => {
                let $b = $($borrow)+ $table.points;
                $body
            }
            LightKind::Spot => {
                let $b = $($borrow)+ $table.spots;
                $body
            }
            LightKind::Area => {
                let $b = $($borrow)+ $table.area;
                $body
            }
            LightKind::Projection => {
                let $b = $($borrow)+ $table.projection;
                $body
            }
            LightKind::Goniometric => {
                let $b = $($borrow)+ $table.goniometric;
                $body
            }
            LightKind::Distant => {
                let $b = $($borrow)+ $table.distant;
                $body
            }
            LightKind::UniformInfinite => {
                let $b = $($borrow)+ $table.uniform_infinite;
                $body
            }
            LightKind::ImageInfinite => {
                let $b = $($borrow)+ $table.image_infinite;
                $body
            }
            LightKind::SunSky => {
                let $b = $($borrow)+ $table.sun_sky;
                $body
            }
        }
    };
}

impl LightTable {
    /// Number of lights (rows) of every kind.
    pub fn len(&self) -> usize {
        LightKind::ALL.iter().map(|&kind| self.kind_len(kind)).sum()
    }
    /// Number of rows of one kind.
    pub fn kind_len(&self, kind: LightKind) -> usize {
        for_block!(ref self, kind, |b| b.len())
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
    /// Every light id, kind by kind in [`LightKind::ALL`] order.
    pub fn ids(&self) -> impl Iterator<Item = LightId> + '_ {
        LightKind::ALL
            .into_iter()
            .flat_map(|kind| (0..self.kind_len(kind) as u32).map(move |row| LightId { kind, row }))
    }
    /// The entity that owns light `id`.
    pub fn owner(&self, id: LightId) -> Entity {
        for_block!(ref self, id.kind, |b| b.owner(id.row as usize))
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

    /// Inserts or replaces the area-light rows of `entity` (one per emitting shape or triangle,
    /// in increasing `primitive` order): in place when the count is unchanged (a moving light).
    pub fn upsert_area(&mut self, entity: Entity, rows: Vec<AreaRow>, casts_shadows: bool, power_changed: bool) {
        self.generation += 1;
        let same = self
            .rows_of
            .get(&entity)
            .is_some_and(|ids| ids.len() == rows.len() && ids.iter().all(|id| id.kind == LightKind::Area));
        if same {
            let ids = self.rows_of[&entity].clone();
            for (id, row) in ids.iter().zip(rows) {
                self.area.set(id.row as usize, row, casts_shadows);
            }
            self.moved = true;
            self.powers_changed |= power_changed;
            return;
        }
        self.remove(entity);
        if rows.is_empty() {
            return;
        }
        let first = self.area.len() as u32;
        let n = rows.len() as u32;
        for row in rows {
            self.area.push(entity, row, casts_shadows);
        }
        self.rows_of.insert(entity, (first..first + n).map(|row| LightId { kind: LightKind::Area, row }).collect());
        self.powers_changed = true;
    }

    /// The area light on `entity`'s `primitive` (its triangle index, 0 for shapes), if any.
    pub fn area_light_at(&self, entity: Entity, primitive: u32) -> Option<LightId> {
        self.area_light_among(self.rows_of.get(&entity)?, primitive)
    }

    /// The area light on `primitive` among one entity's rows (`rows_of`), if any: for callers
    /// that looked the rows up once per entity.
    pub fn area_light_among(&self, ids: &[LightId], primitive: u32) -> Option<LightId> {
        let k = ids
            .binary_search_by_key(&primitive, |id| {
                if id.kind == LightKind::Area { self.area.items[id.row as usize].primitive } else { u32::MAX }
            })
            .ok()?;
        Some(ids[k])
    }

    /// See [`Self::upsert_point`].
    pub fn upsert_projection(
        &mut self,
        entity: Entity,
        row: ResolvedProjection,
        casts_shadows: bool,
        power_changed: bool,
    ) {
        self.upsert(entity, LightKind::Projection, power_changed, |t| &mut t.projection, row, casts_shadows);
    }
    /// See [`Self::upsert_point`].
    pub fn upsert_goniometric(
        &mut self,
        entity: Entity,
        row: ResolvedGoniometric,
        casts_shadows: bool,
        power_changed: bool,
    ) {
        self.upsert(entity, LightKind::Goniometric, power_changed, |t| &mut t.goniometric, row, casts_shadows);
    }
    /// See [`Self::upsert_point`].
    pub fn upsert_uniform_infinite(&mut self, entity: Entity, row: ResolvedUniformInfinite, power_changed: bool) {
        self.upsert(entity, LightKind::UniformInfinite, power_changed, |t| &mut t.uniform_infinite, row, true);
    }
    /// See [`Self::upsert_point`].
    pub fn upsert_image_infinite(&mut self, entity: Entity, row: ResolvedImageInfinite, power_changed: bool) {
        self.upsert(entity, LightKind::ImageInfinite, power_changed, |t| &mut t.image_infinite, row, true);
    }

    /// See [`Self::upsert_point`].
    pub fn upsert_sun_sky(&mut self, entity: Entity, row: ResolvedSunSky, power_changed: bool) {
        self.upsert(entity, LightKind::SunSky, power_changed, |t| &mut t.sun_sky, row, true);
    }

    /// The sun-and-sky row of `entity`, if it has one.
    pub fn sun_sky_of(&self, entity: Entity) -> Option<&ResolvedSunSky> {
        let id = self.rows_of(entity).iter().find(|id| id.kind == LightKind::SunSky)?;
        self.sun_sky.items.get(id.row as usize)
    }

    /// Takes the sky buffers out of `entity`'s sun-and-sky row (leaving it empty until its next
    /// upsert), so a rebuild can reuse them; fresh buffers if it has none.
    pub fn take_sun_sky_buffers(&mut self, entity: Entity) -> super::infinite::sunsky::SkyBuffers {
        let Some(id) = self.rows_of(entity).iter().find(|id| id.kind == LightKind::SunSky).copied() else {
            return Default::default();
        };
        let row = &mut self.sun_sky.items[id.row as usize];
        std::sync::Arc::try_unwrap(std::mem::take(&mut row.buffers)).unwrap_or_default()
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

    /// Where each kind's rows start in the order of [`Self::ids`], indexed by
    /// [`LightKind::index`]: light `id` is number `offsets[id.kind.index()] + id.row`.
    pub fn kind_offsets(&self) -> [u32; LightKind::COUNT] {
        let mut offsets = [0u32; LightKind::COUNT];
        for k in 1..LightKind::COUNT {
            offsets[k] = offsets[k - 1] + self.kind_len(LightKind::ALL[k - 1]) as u32;
        }
        offsets
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
