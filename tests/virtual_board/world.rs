//! The scripted world of the virtual board: one clock, the physical neck, the HC-SR04 on it,
//! the e-stop button, the wheels' counters, the battery and the two motor bridges, behind
//! embedded-hal 1.0 pins (and the three small traits of `twil_core::drivers`).
//!
//! Time moves only when the code under test waits (`DelayNs`, an echo capture waiting for an
//! edge) or when the test's scheduler moves it to the next event, so every run is exact and
//! repeatable. The world checks the data sheets' timing as the parts would: a step whose
//! direction changed less than 650 ns before it (DRV8825 t_SU) is lost, a step pulse shorter
//! than 1.9 µs is counted, a trigger shorter than 10 µs or sent while the echo line is still
//! high is ignored (HC-SR04). The echo line rises 450 µs after the trigger (the burst and the
//! module's start; a script figure: the width alone carries the range) and stays high for the
//! round trip at 343.2 m/s, or 38 ms with no target.

use std::cell::RefCell;
use std::collections::VecDeque;
use std::convert::Infallible;
use std::rc::Rc;

use embedded_hal::delay::DelayNs;
use embedded_hal::digital::{ErrorType, InputPin, OutputPin};
use embedded_hal::pwm::SetDutyCycle;
use twil_core::drivers::{
    BatteryReadError, BatterySensor, EchoCapture, EchoEdge, QuadratureCounter,
};

/// Speed of sound of the scripted air, m/s (the core's).
pub const SOUND_M_S: f64 = 343.2;
/// Echo rise after the trigger's fall, ns.
pub const ECHO_RISE_NS: u64 = 450_000;
/// The no-target pulse, ns.
pub const NO_TARGET_NS: u64 = 38_000_000;
/// Degrees per neck step.
pub const STEP_DEG: f32 = 1.8;
/// PWM counts for 100 %.
pub const MAX_DUTY: u16 = 4199;

/// Everything the world is and has seen.
pub struct State {
    /// The clock, ns.
    pub now_ns: u64,
    // --- the script
    /// Range of the nearest target seen at a physical neck angle (degrees), or none.
    pub range_at_deg: Box<dyn Fn(f32) -> Option<f32>>,
    /// The sonar answers triggers (false: unplugged).
    pub sonar_answers: bool,
    /// A 2 µs spike before each echo and a 3 µs dip inside it (motor PWM coupling).
    pub pwm_noise: bool,
    /// The e-stop is pressed from these times on (ns) until the next release time.
    pub estop_pressed_at_ns: Vec<(u64, u64)>,
    /// Battery volts, and a sag of `sag_v_per_s` from `sag_from_ns` on.
    pub battery_v: f32,
    /// Start of the sag, ns.
    pub sag_from_ns: Option<u64>,
    /// Sag rate, V/s.
    pub sag_v_per_s: f32,
    /// The battery's ADC fails.
    pub battery_fails: bool,
    /// Raw counter speeds (left, right), counts per second (negative: counting down).
    pub counts_per_s: (f64, f64),
    /// Raw counters at time 0.
    pub counter_start: (u16, u16),
    /// Wheels driven by their motors (the self-test's pulses): forward counts per second per
    /// volt applied (duty × battery), left and right; 0 (the default) leaves the counters to
    /// [`State::counts_per_s`] alone. The right encoder is mounted mirrored, as the board's.
    pub counts_per_s_per_v: [f64; 2],
    /// An encoder's A and B wires swapped: it counts the other way.
    pub encoder_swapped: [bool; 2],
    driven_counts: [f64; 2],
    driven_at_ns: u64,
    /// The home switch closes at or below [`State::home_at_steps`] (false: broken).
    pub home_switch_works: bool,
    /// Where the home switch is, steps from straight ahead.
    pub home_at_steps: i32,
    // --- the physical neck
    /// Where the neck really is, steps.
    pub neck_steps: i32,
    dir_high: bool,
    dir_changed_ns: u64,
    step_high_since: Option<u64>,
    /// Step rising edges, ns.
    pub step_times_ns: Vec<u64>,
    /// Steps lost to a direction set-up shorter than 650 ns.
    pub setup_violations: u32,
    /// Step pulses shorter than 1.9 µs.
    pub short_step_pulses: u32,
    // --- the sonar
    trigger_high_since: Option<u64>,
    /// Triggers the module answered: (time, physical neck angle, scripted range).
    pub pings: Vec<(u64, f32, Option<f32>)>,
    /// Triggers ignored (too short, or the module busy).
    pub ignored_triggers: u32,
    echo_edges: VecDeque<(u64, bool)>,
    echo_busy_until_ns: u64,
    // --- the motors
    /// Duty counts and direction level (left, right).
    pub duty: [(u16, bool); 2],
    /// Every duty set: (time, side, counts).
    pub duty_log: Vec<(u64, usize, u16)>,
}

/// The world, shared by every pin.
#[derive(Clone)]
pub struct World(pub Rc<RefCell<State>>);

impl World {
    /// A quiet world: nothing in range, the e-stop released, a 12.6 V battery, wheels still,
    /// the neck 30 steps off straight ahead, the home switch at −102 steps.
    pub fn new() -> Self {
        World(Rc::new(RefCell::new(State {
            now_ns: 0,
            range_at_deg: Box::new(|_| None),
            sonar_answers: true,
            pwm_noise: false,
            estop_pressed_at_ns: Vec::new(),
            battery_v: 12.6,
            sag_from_ns: None,
            sag_v_per_s: 0.0,
            battery_fails: false,
            counts_per_s: (0.0, 0.0),
            counter_start: (0, 0),
            counts_per_s_per_v: [0.0; 2],
            encoder_swapped: [false; 2],
            driven_counts: [0.0; 2],
            driven_at_ns: 0,
            home_switch_works: true,
            home_at_steps: -102,
            neck_steps: 30,
            dir_high: false,
            dir_changed_ns: 0,
            step_high_since: None,
            step_times_ns: Vec::new(),
            setup_violations: 0,
            short_step_pulses: 0,
            trigger_high_since: None,
            pings: Vec::new(),
            ignored_triggers: 0,
            echo_edges: VecDeque::new(),
            echo_busy_until_ns: 0,
            duty: [(0, false); 2],
            duty_log: Vec::new(),
        })))
    }

    /// The clock, ns.
    pub fn now_ns(&self) -> u64 {
        self.0.borrow().now_ns
    }

    /// Move the clock to `t_ns` (never back).
    pub fn advance_to(&self, t_ns: u64) {
        let mut s = self.0.borrow_mut();
        s.now_ns = s.now_ns.max(t_ns);
    }

    /// The next echo edge at or after `from_ns`, if any is scheduled.
    pub fn next_echo_edge_ns(&self, from_ns: u64) -> Option<u64> {
        let s = self.0.borrow();
        s.echo_edges.iter().map(|e| e.0).find(|&t| t >= from_ns)
    }

    /// Pins of every kind.
    pub fn pin(&self, kind: PinKind) -> Pin {
        Pin {
            world: self.clone(),
            kind,
        }
    }
}

impl State {
    /// Whether the e-stop is pressed now.
    pub fn estop_pressed(&self) -> bool {
        self.estop_pressed_at_ns
            .iter()
            .any(|&(from, to)| self.now_ns >= from && self.now_ns < to)
    }

    fn battery_now_v(&self) -> f32 {
        match self.sag_from_ns {
            Some(from) if self.now_ns > from => {
                self.battery_v - self.sag_v_per_s * ((self.now_ns - from) as f32 * 1e-9)
            }
            _ => self.battery_v,
        }
    }

    /// Move the driven wheels up to now at the duty and direction they have had since the last
    /// change (the left bridge's direction high is forward, the right's low: mirrored).
    fn integrate_wheels(&mut self) {
        let dt_s = self.now_ns.saturating_sub(self.driven_at_ns) as f64 * 1e-9;
        self.driven_at_ns = self.now_ns;
        let battery_v = f64::from(self.battery_now_v());
        for side in 0..2 {
            let (duty, dir_high) = self.duty[side];
            let forward = dir_high == (side == 0);
            let volts = f64::from(duty) / f64::from(MAX_DUTY) * battery_v;
            let mut raw = self.counts_per_s_per_v[side] * volts * dt_s;
            if !forward {
                raw = -raw;
            }
            if side == 1 {
                raw = -raw;
            }
            if self.encoder_swapped[side] {
                raw = -raw;
            }
            self.driven_counts[side] += raw;
        }
    }

    fn step_rise(&mut self) {
        self.step_high_since = Some(self.now_ns);
        self.step_times_ns.push(self.now_ns);
        if self.now_ns.saturating_sub(self.dir_changed_ns) < 650 {
            self.setup_violations += 1;
            return;
        }
        self.neck_steps += if self.dir_high { 1 } else { -1 };
    }

    fn trigger_fall(&mut self, since_ns: u64) {
        let now = self.now_ns;
        if now - since_ns < 10_000 || now < self.echo_busy_until_ns {
            self.ignored_triggers += 1;
            return;
        }
        if !self.sonar_answers {
            return;
        }
        let angle_deg = self.neck_steps as f32 * STEP_DEG;
        let range_m = (self.range_at_deg)(angle_deg);
        let width_ns = range_m.map_or(NO_TARGET_NS, |r| {
            (2.0 * f64::from(r) / SOUND_M_S * 1e9).round() as u64
        });
        let rise = now + ECHO_RISE_NS;
        let fall = rise + width_ns;
        if self.pwm_noise {
            self.echo_edges.push_back((now + 200_000, true));
            self.echo_edges.push_back((now + 202_000, false));
        }
        self.echo_edges.push_back((rise, true));
        if self.pwm_noise {
            let mid = rise + width_ns / 2;
            self.echo_edges.push_back((mid, false));
            self.echo_edges.push_back((mid + 3_000, true));
        }
        self.echo_edges.push_back((fall, false));
        self.echo_busy_until_ns = fall;
        self.pings.push((now, angle_deg, range_m));
    }
}

/// What a [`Pin`] is.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum PinKind {
    /// Neck step output.
    Step,
    /// Neck direction output (high = positive).
    Dir,
    /// Neck home switch input (closed = low).
    Home,
    /// Sonar trigger output.
    Trigger,
    /// E-stop input (pressed = high).
    Estop,
    /// A motor's direction output (0 left, 1 right).
    MotorDir(usize),
}

/// A pin of the world.
pub struct Pin {
    world: World,
    kind: PinKind,
}

impl ErrorType for Pin {
    type Error = Infallible;
}

impl OutputPin for Pin {
    fn set_high(&mut self) -> Result<(), Infallible> {
        let mut s = self.world.0.borrow_mut();
        match self.kind {
            PinKind::Step => {
                if s.step_high_since.is_none() {
                    s.step_rise();
                }
            }
            PinKind::Dir => {
                if !s.dir_high {
                    s.dir_high = true;
                    s.dir_changed_ns = s.now_ns;
                }
            }
            PinKind::Trigger => {
                if s.trigger_high_since.is_none() {
                    s.trigger_high_since = Some(s.now_ns);
                }
            }
            PinKind::MotorDir(side) => {
                s.integrate_wheels();
                s.duty[side].1 = true
            }
            PinKind::Home | PinKind::Estop => {}
        }
        Ok(())
    }

    fn set_low(&mut self) -> Result<(), Infallible> {
        let mut s = self.world.0.borrow_mut();
        match self.kind {
            PinKind::Step => {
                if let Some(since) = s.step_high_since.take() {
                    if s.now_ns - since < 1_900 {
                        s.short_step_pulses += 1;
                    }
                }
            }
            PinKind::Dir => {
                if s.dir_high {
                    s.dir_high = false;
                    s.dir_changed_ns = s.now_ns;
                }
            }
            PinKind::Trigger => {
                if let Some(since) = s.trigger_high_since.take() {
                    s.trigger_fall(since);
                }
            }
            PinKind::MotorDir(side) => {
                s.integrate_wheels();
                s.duty[side].1 = false
            }
            PinKind::Home | PinKind::Estop => {}
        }
        Ok(())
    }
}

impl InputPin for Pin {
    fn is_high(&mut self) -> Result<bool, Infallible> {
        let s = self.world.0.borrow();
        Ok(match self.kind {
            PinKind::Home => !(s.home_switch_works && s.neck_steps <= s.home_at_steps),
            PinKind::Estop => s.estop_pressed(),
            _ => false,
        })
    }

    fn is_low(&mut self) -> Result<bool, Infallible> {
        self.is_high().map(|h| !h)
    }
}

/// Waits move the clock.
pub struct Delay(pub World);

impl DelayNs for Delay {
    fn delay_ns(&mut self, ns: u32) {
        self.0 .0.borrow_mut().now_ns += u64::from(ns);
    }
}

/// The echo line, timed at 1 MHz.
pub struct Echo {
    /// The world.
    pub world: World,
    armed_ns: u64,
}

impl Echo {
    /// The echo line of `world`.
    pub fn new(world: World) -> Self {
        Self { world, armed_ns: 0 }
    }
}

impl EchoCapture for Echo {
    fn tick_hz(&self) -> u32 {
        1_000_000
    }

    fn arm(&mut self) {
        let mut s = self.world.0.borrow_mut();
        self.armed_ns = s.now_ns;
        let now = s.now_ns;
        s.echo_edges.retain(|e| e.0 >= now);
    }

    fn next_edge(&mut self, deadline_ticks: u32) -> Option<EchoEdge> {
        let mut s = self.world.0.borrow_mut();
        let deadline_ns = self.armed_ns + u64::from(deadline_ticks) * 1_000;
        match s.echo_edges.front().copied() {
            Some((t, rising)) if t <= deadline_ns => {
                s.echo_edges.pop_front();
                s.now_ns = s.now_ns.max(t);
                Some(EchoEdge {
                    rising,
                    at_ticks: ((t - self.armed_ns) / 1_000) as u32,
                })
            }
            _ => {
                s.now_ns = s.now_ns.max(deadline_ns);
                None
            }
        }
    }

    fn elapsed_ticks(&mut self) -> u32 {
        let s = self.world.0.borrow();
        ((s.now_ns - self.armed_ns) / 1_000) as u32
    }
}

/// A motor bridge's PWM input (0 left, 1 right).
pub struct Pwm(pub World, pub usize);

impl embedded_hal::pwm::ErrorType for Pwm {
    type Error = Infallible;
}

impl SetDutyCycle for Pwm {
    fn max_duty_cycle(&self) -> u16 {
        MAX_DUTY
    }

    fn set_duty_cycle(&mut self, duty: u16) -> Result<(), Infallible> {
        let mut s = self.0 .0.borrow_mut();
        s.integrate_wheels();
        s.duty[self.1].0 = duty;
        let now = s.now_ns;
        s.duty_log.push((now, self.1, duty));
        Ok(())
    }
}

/// A wheel's quadrature counter (0 left, 1 right).
pub struct Counter(pub World, pub usize);

impl QuadratureCounter for Counter {
    fn count(&mut self) -> u16 {
        let mut s = self.0 .0.borrow_mut();
        s.integrate_wheels();
        let (rate, start) = if self.1 == 0 {
            (s.counts_per_s.0, s.counter_start.0)
        } else {
            (s.counts_per_s.1, s.counter_start.1)
        };
        let moved = (rate * s.now_ns as f64 * 1e-9 + s.driven_counts[self.1]).round() as i64;
        (i64::from(start) + moved).rem_euclid(65_536) as u16
    }
}

/// The battery's ADC.
pub struct Battery(pub World);

impl BatterySensor for Battery {
    fn read_battery_v(&mut self) -> Result<f32, BatteryReadError> {
        let s = self.0 .0.borrow();
        if s.battery_fails {
            Err(BatteryReadError)
        } else {
            Ok(s.battery_now_v())
        }
    }
}
