//! The `bevy` feature: [`LightingPlugin`] as a `bevy_app::Plugin`, with lights and geometry placed
//! by Bevy's `GlobalTransform`, so an entity keeps the one transform Bevy propagates.

use bevy_app::{App, Plugin, PostUpdate};
use bevy_ecs::schedule::{IntoScheduleConfigs, ScheduleLabel};
use bevy_transform::TransformSystems;
use bevy_transform::components::{GlobalTransform, Transform};

use super::{LightingPlugin, LightingSet, add_systems, init_resources, require_placement};

impl Default for LightingPlugin {
    /// Runs in `PostUpdate`, after transform propagation.
    fn default() -> Self {
        Self { schedule: PostUpdate.intern() }
    }
}

impl LightingPlugin {
    /// The plugin with its systems in `schedule` (for example `Update`, or a schedule the app
    /// runs on demand). They still run after transform propagation if the schedule has it.
    pub fn in_schedule(schedule: impl ScheduleLabel) -> Self {
        Self { schedule: schedule.intern() }
    }
}

impl Plugin for LightingPlugin {
    fn build(&self, app: &mut App) {
        init_resources(app.world_mut());
        // Bevy's Transform brings its GlobalTransform, which is what the systems read.
        require_placement::<Transform>(app.world_mut());
        app.edit_schedule(self.schedule, |schedule| {
            add_systems::<GlobalTransform>(schedule);
            // Lights and geometry are placed where propagation has just put them.
            schedule.configure_sets(LightingSet::UpdateBvh.after(TransformSystems::Propagate));
        });
    }
}
