//! Object motion after the paper's test sequences: hand-held translation, rotation, shaking, throw-and-catch
//! with spin, hand-to-hand switches and depth changes, at three speed levels. Deterministic from a seed.
//!
//! A trajectory is `T_cam_obj(t)` in the event camera frame (OpenCV axes, metres); gravity is +y (the camera
//! looks horizontally). Every profile is smooth while the object is held; a throw's flight is ballistic.

use crate::rng::SeedRng;
use nalgebra::{Isometry3, Translation3, UnitQuaternion, Vector3};
use std::f64::consts::{PI, TAU};
use std::fmt;
use std::str::FromStr;

/// Which kind of motion.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum MotionProfile {
    /// Translation-dominant hand-held motion with a little rotation.
    Translation,
    /// Rotation-dominant: the object turns in the hand, little translation.
    Rotation,
    /// Fast small-amplitude shaking with wrist rotation.
    Shake,
    /// Thrown from hand to hand, spinning in flight.
    ThrowCatch,
    /// Carried across and passed from one hand to the other.
    HandSwitch,
    /// Moved towards and away from the camera.
    DepthVariation,
}

impl MotionProfile {
    /// Every profile.
    pub const ALL: [MotionProfile; 6] = [
        MotionProfile::Translation,
        MotionProfile::Rotation,
        MotionProfile::Shake,
        MotionProfile::ThrowCatch,
        MotionProfile::HandSwitch,
        MotionProfile::DepthVariation,
    ];

    /// Command-line name.
    pub fn name(self) -> &'static str {
        match self {
            MotionProfile::Translation => "translation",
            MotionProfile::Rotation => "rotation",
            MotionProfile::Shake => "shake",
            MotionProfile::ThrowCatch => "throw",
            MotionProfile::HandSwitch => "hand-switch",
            MotionProfile::DepthVariation => "depth",
        }
    }
}

impl fmt::Display for MotionProfile {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

impl FromStr for MotionProfile {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        Self::ALL
            .into_iter()
            .find(|p| p.name() == s)
            .ok_or_else(|| {
                let names: Vec<&str> = Self::ALL.iter().map(|p| p.name()).collect();
                format!(
                    "unknown motion profile `{s}` (one of: {})",
                    names.join(", ")
                )
            })
    }
}

/// How fast.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum SpeedLevel {
    /// About 0.3 m/s, up to about 2 rad/s.
    Slow,
    /// About 1 m/s, up to about 6 rad/s.
    Moderate,
    /// About 2 m/s average, up to about 15 rad/s.
    Fast,
}

impl SpeedLevel {
    /// Every level.
    pub const ALL: [SpeedLevel; 3] = [SpeedLevel::Slow, SpeedLevel::Moderate, SpeedLevel::Fast];

    /// Command-line name.
    pub fn name(self) -> &'static str {
        match self {
            SpeedLevel::Slow => "slow",
            SpeedLevel::Moderate => "moderate",
            SpeedLevel::Fast => "fast",
        }
    }

    /// Target average linear speed of the object centre, m/s.
    pub fn linear_mps(self) -> f64 {
        match self {
            SpeedLevel::Slow => 0.3,
            SpeedLevel::Moderate => 1.0,
            SpeedLevel::Fast => 2.0,
        }
    }

    /// Target peak angular speed, rad/s.
    pub fn angular_radps(self) -> f64 {
        match self {
            SpeedLevel::Slow => 2.0,
            SpeedLevel::Moderate => 6.0,
            SpeedLevel::Fast => 15.0,
        }
    }
}

impl fmt::Display for SpeedLevel {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

impl FromStr for SpeedLevel {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        Self::ALL
            .into_iter()
            .find(|p| p.name() == s)
            .ok_or_else(|| format!("unknown speed level `{s}` (one of: slow, moderate, fast)"))
    }
}

/// One sinusoid per axis: `amp * sin(freq * u + phase)`.
#[derive(Debug, Clone, Copy, PartialEq)]
struct Wave {
    amp: Vector3<f64>,
    freq: Vector3<f64>,
    phase: Vector3<f64>,
}

impl Wave {
    fn at(&self, u: f64) -> Vector3<f64> {
        Vector3::from_fn(|i, _| self.amp[i] * (self.freq[i] * u + self.phase[i]).sin())
    }
}

/// A deterministic object trajectory.
#[derive(Debug, Clone, PartialEq)]
pub struct Trajectory {
    profile: MotionProfile,
    speed: SpeedLevel,
    centre: Vector3<f64>,
    start_rotation: UnitQuaternion<f64>,
    position: Wave,
    rotation: Wave,
    spin_axis: Vector3<f64>,
    /// Time scales applied to the base waves (chosen so the targets are met).
    pos_scale: f64,
    rot_scale: f64,
    /// Throw / hand-switch: one crossing lasts this long, seconds.
    cycle_s: f64,
    span_m: f64,
}

/// Distance of the object centre from the camera at rest, metres.
pub const WORKING_DISTANCE_M: f64 = 0.65;

impl Trajectory {
    /// A trajectory of `profile` at `speed`; `seed` chooses phases, axes and the start orientation.
    pub fn new(profile: MotionProfile, speed: SpeedLevel, seed: u64) -> Self {
        let mut rng = SeedRng::new(seed ^ 0x5EED);
        let centre = Vector3::new(
            rng.range(-0.03, 0.03),
            rng.range(-0.03, 0.02),
            WORKING_DISTANCE_M,
        );
        let start_rotation =
            UnitQuaternion::from_scaled_axis(rng.unit_vector() * rng.range(0.0, PI));
        let phase = Vector3::new(
            rng.range(0.0, TAU),
            rng.range(0.0, TAU),
            rng.range(0.0, TAU),
        );
        let rphase = Vector3::new(
            rng.range(0.0, TAU),
            rng.range(0.0, TAU),
            rng.range(0.0, TAU),
        );
        let (pos_amp, pos_freq, rot_amp, rot_freq) = match profile {
            MotionProfile::Translation => (
                Vector3::new(0.14, 0.09, 0.05),
                Vector3::new(1.0, 1.37, 0.71),
                Vector3::new(0.25, 0.2, 0.15),
                Vector3::new(0.6, 0.9, 0.5),
            ),
            MotionProfile::Rotation => (
                Vector3::new(0.03, 0.02, 0.02),
                Vector3::new(1.0, 1.3, 0.8),
                Vector3::new(0.5, 0.4, 0.3),
                Vector3::new(1.0, 1.4, 0.7),
            ),
            MotionProfile::Shake => (
                Vector3::new(0.06, 0.015, 0.01),
                Vector3::new(1.0, 2.0, 1.5),
                Vector3::new(0.35, 0.1, 0.1),
                Vector3::new(1.0, 2.0, 1.0),
            ),
            MotionProfile::DepthVariation => (
                Vector3::new(0.03, 0.02, 0.18),
                Vector3::new(0.8, 1.1, 1.0),
                Vector3::new(0.2, 0.2, 0.1),
                Vector3::new(0.5, 0.7, 0.4),
            ),
            MotionProfile::ThrowCatch | MotionProfile::HandSwitch => (
                Vector3::new(0.01, 0.01, 0.01),
                Vector3::new(3.0, 2.0, 2.5),
                Vector3::new(0.1, 0.1, 0.1),
                Vector3::new(1.0, 1.0, 1.0),
            ),
        };
        let mut t = Self {
            profile,
            speed,
            centre,
            start_rotation,
            position: Wave {
                amp: pos_amp,
                freq: pos_freq,
                phase,
            },
            rotation: Wave {
                amp: rot_amp,
                freq: rot_freq,
                phase: rphase,
            },
            spin_axis: rng.unit_vector(),
            pos_scale: 1.0,
            rot_scale: 1.0,
            cycle_s: 1.0,
            span_m: 0.36,
        };
        t.calibrate();
        t
    }

    /// The profile.
    pub fn profile(&self) -> MotionProfile {
        self.profile
    }

    /// The speed level.
    pub fn speed(&self) -> SpeedLevel {
        self.speed
    }

    /// Chooses time scales so that the average linear speed and the peak angular speed meet the level's targets.
    fn calibrate(&mut self) {
        let lin = self.speed.linear_mps();
        let ang = self.speed.angular_radps();
        match self.profile {
            MotionProfile::ThrowCatch | MotionProfile::HandSwitch => {
                // One crossing of span_m, its duration adjusted until the mean speed (arc included) is the target.
                self.cycle_s = self.span_m / lin;
                for _ in 0..4 {
                    let (mean_lin, _) = self.measure(8.0 * self.cycle_s, 4000);
                    self.cycle_s *= mean_lin / lin;
                }
            }
            _ => {
                let (lin_share, ang_share) = match self.profile {
                    MotionProfile::Rotation => (0.35, 1.0),
                    MotionProfile::Translation | MotionProfile::DepthVariation => (1.0, 0.5),
                    _ => (0.8, 1.0),
                };
                let (mean_lin, _) = self.measure(4.0, 2000);
                self.pos_scale *= lin * lin_share / mean_lin.max(1e-9);
                let (_, peak_ang) = self.measure(4.0, 2000);
                self.rot_scale *= ang * ang_share / peak_ang.max(1e-9);
            }
        }
    }

    /// `(mean linear speed, peak angular speed)` over `[0, seconds]` sampled at `n` steps.
    pub fn measure(&self, seconds: f64, n: usize) -> (f64, f64) {
        let dt = seconds / n as f64;
        let mut sum = 0.0;
        let mut peak: f64 = 0.0;
        let mut prev = self.pose(0.0);
        for i in 1..=n {
            let p = self.pose(i as f64 * dt);
            sum += (p.translation.vector - prev.translation.vector).norm() / dt;
            peak = peak.max(p.rotation.angle_to(&prev.rotation) / dt);
            prev = p;
        }
        (sum / n as f64, peak)
    }

    /// Whether a hand holds the object at `t_s`, and which (`0` left, `1` right).
    pub fn holding_hand(&self, t_s: f64) -> Option<usize> {
        match self.profile {
            MotionProfile::ThrowCatch => {
                let (k, u) = self.cycle_phase(t_s);
                // Held for the first and last 15 % of each crossing; flying in between.
                let side = (k % 2) as usize;
                if u < 0.15 {
                    Some(side)
                } else if u > 0.85 {
                    Some(1 - side)
                } else {
                    None
                }
            }
            MotionProfile::HandSwitch => {
                let (k, u) = self.cycle_phase(t_s);
                let side = (k % 2) as usize;
                Some(if u < 0.5 { side } else { 1 - side })
            }
            _ => Some(1),
        }
    }

    fn cycle_phase(&self, t_s: f64) -> (u64, f64) {
        let c = (t_s / self.cycle_s).max(0.0);
        (c.floor() as u64, c.fract())
    }

    /// `T_cam_obj` at `t_s` seconds.
    pub fn pose(&self, t_s: f64) -> Isometry3<f64> {
        let (offset, rotvec) = match self.profile {
            MotionProfile::ThrowCatch => self.throw(t_s),
            MotionProfile::HandSwitch => self.switch(t_s),
            _ => (
                self.position.at(t_s * self.pos_scale),
                self.rotation.at(t_s * self.rot_scale),
            ),
        };
        let rotation = UnitQuaternion::from_scaled_axis(rotvec) * self.start_rotation;
        Isometry3::from_parts(Translation3::from(self.centre + offset), rotation)
    }

    /// Ballistic flight between two hands `span_m` apart, spinning at the level's angular speed.
    fn throw(&self, t_s: f64) -> (Vector3<f64>, Vector3<f64>) {
        let (k, u) = self.cycle_phase(t_s);
        let dir = if k % 2 == 0 { 1.0 } else { -1.0 };
        let half = self.span_m / 2.0;
        // x crosses linearly (constant horizontal velocity), y follows a parabola under gravity.
        let x = dir * (-half + self.span_m * u);
        let flight = self.cycle_s;
        // Apex height of a throw of this duration under gravity, capped at arm's reach.
        let apex = (9.81 * flight * flight / 8.0).min(0.1);
        let y = -4.0 * apex * u * (1.0 - u);
        let spin_angle = self.speed.angular_radps() * t_s;
        let wobble = self.position.at(t_s * 6.0);
        (
            Vector3::new(x, y, 0.0) + wobble,
            self.spin_axis * spin_angle,
        )
    }

    /// Smooth carry from one side to the other with a quarter turn, hands swapping mid-way.
    fn switch(&self, t_s: f64) -> (Vector3<f64>, Vector3<f64>) {
        let (k, u) = self.cycle_phase(t_s);
        let dir = if k % 2 == 0 { 1.0 } else { -1.0 };
        let half = self.span_m / 2.0;
        // Cosine ease: average speed span/cycle, zero at the ends.
        let s = 0.5 - 0.5 * (PI * u).cos();
        let x = dir * (-half + self.span_m * s);
        let y = -0.04 * (PI * u).sin();
        let turns = k as f64 + s;
        let rot = self.spin_axis * (turns * PI / 2.0).min(self.speed.angular_radps() * t_s);
        (Vector3::new(x, y, 0.0) + self.position.at(t_s * 3.0), rot)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn speed_levels_meet_their_targets() {
        for profile in MotionProfile::ALL {
            for speed in SpeedLevel::ALL {
                let t = Trajectory::new(profile, speed, 7);
                let (lin, ang) = t.measure(4.0, 8000);
                let target = speed.linear_mps();
                let share = if profile == MotionProfile::Rotation {
                    0.35
                } else {
                    0.8
                };
                assert!(
                    lin > target * share * 0.7 && lin < target * 1.35,
                    "{profile} {speed}: mean linear speed {lin:.2} m/s for target {target}"
                );
                assert!(
                    ang < speed.angular_radps() * 1.5 + 1.0,
                    "{profile} {speed}: peak angular {ang:.1} rad/s"
                );
            }
        }
    }

    #[test]
    fn fast_profiles_stay_in_view() {
        for profile in MotionProfile::ALL {
            let t = Trajectory::new(profile, SpeedLevel::Fast, 3);
            for i in 0..4000 {
                let p = t.pose(i as f64 * 1e-3).translation.vector;
                // Within the event camera's view at fx = 1000 px (half-width 640 px) with margin.
                assert!(p.z > 0.35 && p.z < 1.0, "{profile}: z {}", p.z);
                assert!(
                    (p.x / p.z).abs() < 0.5 && (p.y / p.z).abs() < 0.33,
                    "{profile}: off view {p:?}"
                );
            }
        }
    }

    #[test]
    fn same_seed_same_trajectory_different_seed_different() {
        let a = Trajectory::new(MotionProfile::Shake, SpeedLevel::Fast, 11);
        let b = Trajectory::new(MotionProfile::Shake, SpeedLevel::Fast, 11);
        let c = Trajectory::new(MotionProfile::Shake, SpeedLevel::Fast, 12);
        assert_eq!(a.pose(1.234), b.pose(1.234));
        assert_ne!(a.pose(1.234), c.pose(1.234));
    }

    #[test]
    fn throw_is_free_flight_in_the_middle_of_a_crossing() {
        let t = Trajectory::new(MotionProfile::ThrowCatch, SpeedLevel::Moderate, 1);
        assert_eq!(t.holding_hand(0.01), Some(0));
        assert_eq!(t.holding_hand(t.cycle_s * 0.5), None);
        assert_eq!(t.holding_hand(t.cycle_s * 0.95), Some(1));
    }
}
