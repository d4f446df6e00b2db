//! The self-test's probes on the simulated robot ([`Plant`]): what the QEMU build of the
//! firmware and the in-process device (`--remote sim`) answer.
//!
//! The simulation has wheels, encoders, a sonar and a neck, but no e-stop input and no battery:
//! those probes are [`Answer::Absent`] and their rows `skip`. The neck is ideal (it homes from
//! where it points to the negative limit, ±(180° + margin) as the board's, and never loses a
//! step); a ping casts the sonar's ray on the real world the host uploaded; a pulse drives a
//! copy of the plant, as wheels lifted off the floor, so the simulated robot does not move.

use super::{Answer, CheckBody, Echo, Probe};
use crate::drivers::neck_stepper::NeckGeometry;
use crate::plant::Plant;
use crate::world::{PolygonSet, MAX_POLYGONS, MAX_VERTICES};

/// The simulated robot for [`super::run`], in a world of at most `V` vertices and `P` polygons
/// (a simulated device's world is smaller than the host's, `crate::link::WORLD_VERTICES`).
pub struct SimulatedCheck<'a, const V: usize = MAX_VERTICES, const P: usize = MAX_POLYGONS> {
    /// The robot as it stands (not moved by a pulse).
    pub plant: &'a Plant,
    /// The real world the sonar sees.
    pub world: &'a PolygonSet<V, P>,
    /// The sonar's range, metres.
    pub sonar_range_m: f32,
    /// Where the ideal neck points, steps from ahead; `None` until homed.
    pub neck_steps: Option<i32>,
}

impl<'a, const V: usize, const P: usize> SimulatedCheck<'a, V, P> {
    /// The robot `plant` in `world`, its sonar reaching `sonar_range_m`, the neck not homed.
    pub fn new(plant: &'a Plant, world: &'a PolygonSet<V, P>, sonar_range_m: f32) -> Self {
        Self {
            plant,
            world,
            sonar_range_m,
            neck_steps: None,
        }
    }

    fn geometry(&self) -> NeckGeometry {
        NeckGeometry::from_config(self.plant.config())
    }
}

impl<const V: usize, const P: usize> CheckBody for SimulatedCheck<'_, V, P> {
    fn probe(&mut self, probe: Probe) -> Answer {
        let geometry = self.geometry();
        match probe {
            Probe::EmergencyStop | Probe::Battery => Answer::Absent,
            Probe::NeckHome => {
                let home = geometry.home_offset_steps;
                // Not homed yet: the neck points ahead.
                let from = self.neck_steps.unwrap_or(0);
                self.neck_steps = Some(home);
                Answer::Neck(Ok(from.abs_diff(home)))
            }
            Probe::NeckTo(angle_deg) => {
                let Some(from) = self.neck_steps else {
                    return Answer::Neck(Err(crate::drivers::body::neck_fault(
                        crate::drivers::NeckError::NotHomed,
                    )));
                };
                match crate::drivers::neck_stepper::angle_to_steps(&geometry, angle_deg) {
                    Ok(to) => {
                        // An ideal move: every step arrives.
                        self.neck_steps = Some(to);
                        Answer::Neck(Ok(from.abs_diff(to)))
                    }
                    Err(e) => Answer::Neck(Err(crate::drivers::body::neck_fault(e))),
                }
            }
            Probe::Sonar(angle_deg) => {
                let mut plant = self.plant.clone();
                let range =
                    plant.sonar_range_m(self.world, angle_deg.to_radians(), self.sonar_range_m);
                Answer::Sonar(Ok(match range {
                    Some(range_m) => Echo::Range(range_m),
                    None => Echo::NoTarget,
                }))
            }
            Probe::Pulse {
                side,
                voltage_v,
                on_ms,
                coast_ms,
            } => {
                let mut plant = self.plant.clone();
                let (left_v, right_v) = side.volts(voltage_v);
                let before = plant.encoder_counts();
                plant.step(on_ms as f32 / 1000.0, left_v, right_v);
                plant.step(coast_ms as f32 / 1000.0, 0.0, 0.0);
                let after = plant.encoder_counts();
                let (left, right) = (
                    after.0.wrapping_sub(before.0),
                    after.1.wrapping_sub(before.1),
                );
                Answer::Pulse(Ok(side.of((left, right))))
            }
        }
    }
}
