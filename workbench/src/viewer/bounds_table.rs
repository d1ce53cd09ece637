//! Ghost bounds tabulated over the light's angles while the render thread has nothing to do,
//! so that a light dragged over a lens that holds still is planned by table lookups (as
//! `render --precomputed` plans) instead of tracing every ghost's bounds for each frame.
//!
//! The table is built one angle at a time, from 0° up to the angle `flarebench precompute`
//! covers by default, and only once the render thread has been idle for half a second: a new
//! job waits for at most one angle. An edit
//! makes a new lens, and its table starts again. Only the fast frames use it; the settled
//! frame traces its bounds (the table's rectangles join two neighbouring angles, which costs a
//! little accuracy, docs/performance.md).

use std::sync::Arc;

use flarebench_sdk::LensSystem;
use flarebench_sdk::ghost::bounds::BoundsMode;
use flarebench_sdk::ghost::table::{BoundsTable, angle_steps, default_max_angle_deg};
use ghost_raytrace::plan::BOUNDS_LAMBDA_NM;
use ghost_raytrace::scene::LightSpec;

/// Angle step of the table (degrees): `flarebench precompute`'s default.
const STEP_DEG: f64 = 0.25;

/// Angles computed per chunk: about 50 ms for the Nikon zoom on two cores, the longest a new
/// job waits for the tabulation.
const CHUNK_ANGLES: usize = 1;

/// A lens's bounds table as far as it is built.
#[derive(Debug)]
pub struct BoundsTabulation {
    system: Arc<LensSystem>,
    angles: Vec<f64>,
    /// The first `done.angles_deg.len()` angles of `angles`.
    done: Option<BoundsTable>,
}

impl BoundsTabulation {
    /// A tabulation of `system`'s ghosts from 0° to its default largest angle, nothing
    /// computed yet (`None` when the lens has no paraxial focal length to set that angle).
    pub fn new(system: Arc<LensSystem>) -> Option<BoundsTabulation> {
        let max = default_max_angle_deg(&system).ok()?;
        Some(BoundsTabulation {
            system,
            angles: angle_steps(max, STEP_DEG),
            done: None,
        })
    }

    /// True when this is `system`'s tabulation.
    pub fn is_for(&self, system: &Arc<LensSystem>) -> bool {
        Arc::ptr_eq(&self.system, system) || *self.system == **system
    }

    /// True when `system` has the same ghosts as this tabulation's lens (the same paths
    /// through the same surface count and stop): its rectangles are then where the edited
    /// lens's ghosts start, for a fast frame drawn before the edited lens is tabulated.
    pub fn same_ghosts(&self, system: &LensSystem) -> bool {
        self.system.surfaces.len() == system.surfaces.len()
            && flarebench_sdk::ghost::enumerate_ghosts(&self.system)
                == flarebench_sdk::ghost::enumerate_ghosts(system)
    }

    /// Angles computed so far.
    pub fn angles_done(&self) -> usize {
        self.done.as_ref().map_or(0, |t| t.angles_deg.len())
    }

    /// True when every angle is computed.
    pub fn complete(&self) -> bool {
        self.angles_done() == self.angles.len()
    }

    /// Stops at the angles computed so far (after a failure): the table then covers less.
    pub fn abandon(&mut self) {
        let k = self.angles_done();
        self.angles.truncate(k);
    }

    /// Computes the next chunk of angles.
    pub fn step(&mut self) {
        let k = self.angles_done();
        let chunk = self.angles[k..(k + CHUNK_ANGLES).min(self.angles.len())].to_vec();
        if chunk.is_empty() {
            return;
        }
        match &mut self.done {
            None => {
                self.done = Some(BoundsTable::compute(
                    &self.system,
                    &chunk,
                    BoundsMode::Precise,
                    BOUNDS_LAMBDA_NM,
                    &|| {},
                ));
            }
            Some(t) => {
                // The same lens and ascending angles: it cannot fail; if it did, stop here.
                if t.extend(&self.system, &chunk).is_err() {
                    self.abandon();
                }
            }
        }
    }

    /// The table, when it covers every light's angle.
    pub fn table_for(&self, lights: &[LightSpec]) -> Option<&BoundsTable> {
        let t = self.done.as_ref()?;
        let last = *t.angles_deg.last()?;
        lights.iter().all(|l| l.theta_deg <= last).then_some(t)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use flarebench_sdk::io::read_lens;

    fn heliar() -> Arc<LensSystem> {
        let path =
            std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../lenses/heliar-tronnier.xml");
        Arc::new(read_lens(&path).unwrap().system)
    }

    #[test]
    fn a_changed_radius_keeps_the_ghosts_and_a_removed_surface_does_not() {
        let sys = heliar();
        let t = BoundsTabulation::new(Arc::clone(&sys)).unwrap();
        let mut edited = (*sys).clone();
        edited.surfaces[0].curvature *= 1.02;
        assert!(t.same_ghosts(&edited));
        edited.surfaces.remove(1);
        assert!(!t.same_ghosts(&edited));
    }

    /// Built an angle at a time, each ghost's search continuing from its last rectangle, the
    /// table is the one computation over the same angles makes, bit for bit (a search started
    /// afresh at each angle misses the Heliar's ghost 4 at 17.1°, whose entry region is 0.6 mm
    /// high).
    #[test]
    fn the_table_built_angle_by_angle_is_one_computation() {
        let sys = heliar();
        let mut t = BoundsTabulation::new(Arc::clone(&sys)).unwrap();
        let light = |deg: f64| LightSpec {
            theta_deg: deg,
            ..LightSpec::parse("0,0").unwrap()
        };
        assert!(t.table_for(&[light(0.0)]).is_none(), "nothing computed yet");
        let mut steps = 0;
        while !t.complete() {
            t.step();
            steps += 1;
        }
        assert_eq!(steps, t.angles.len());
        let max = *t.angles.last().unwrap();
        assert!(
            max > 20.0 && max < 40.0,
            "the Heliar's table reaches {max}°"
        );
        assert!(t.table_for(&[light(max + 0.1)]).is_none());
        let chunked = t.table_for(&[light(5.0), light(max)]).unwrap();
        chunked.check_for(&sys).unwrap();
        let whole = BoundsTable::compute(
            &sys,
            &t.angles,
            BoundsMode::Precise,
            BOUNDS_LAMBDA_NM,
            &|| {},
        );
        assert_eq!(chunked.ghosts, whole.ghosts);
        assert_eq!(chunked.angles_deg, whole.angles_deg);
        assert!(chunked.bounds == whole.bounds, "the tables differ");
        assert!(chunked.bounds.iter().flatten().any(Option::is_some));
        // Angles that do not ascend beyond the table's last are refused.
        let mut copy = whole.clone();
        assert!(copy.extend(&sys, &[max]).is_err());
        assert!(copy.extend(&sys, &[max + 2.0, max + 1.0]).is_err());
        assert!(copy.bounds == whole.bounds);
    }

    #[test]
    fn an_abandoned_table_covers_what_was_computed() {
        let mut t = BoundsTabulation::new(heliar()).unwrap();
        t.step();
        t.step();
        t.abandon();
        assert!(t.complete());
        assert_eq!(t.angles_done(), 2);
        let l = LightSpec::parse("0.2,0").unwrap();
        assert!(t.table_for(&[l]).is_some());
    }
}
