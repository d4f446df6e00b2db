//! The board: Twil's signals on an **Olimex STM32-H405** (STM32F405RGT6, 8 MHz crystal, port
//! pins on headers; its own LED is PC12, its button PA0, USB PA11/PA12 with VBUS sensing on
//! PC4, debug PA13/PA14 (and PA15/PB3/PB4 for JTAG): none of them is used here). Wiring only:
//! every rule about the signals lives in `twil_core::drivers`.
//!
//! | signal | pin | peripheral | driver |
//! |---|---|---|---|
//! | host link TX / RX | PA9 / PA10 | USART1 (in `main.rs`) | `link::Device` |
//! | top sonar trigger | PB0 | GPIO push-pull | [`SonarRanger`] |
//! | top sonar echo | PA1 | TIM5 CH2 input capture, both edges, 1 MHz | [`EchoTim5Ch2`] |
//! | bottom sonar trigger | PB1 | GPIO push-pull | [`SonarRanger`] |
//! | bottom sonar echo | PA5 | TIM2 CH1 input capture, both edges, 1 MHz | [`EchoTim2Ch1`] |
//! | neck step / dir | PC8 / PC9 | GPIO push-pull | [`NeckStepper`] |
//! | neck home switch | PC10 | GPIO input, pull-up, closed = low | [`NeckStepper`] |
//! | left motor PWM / dir | PB14 / PB12 | TIM12 CH1 at 20 kHz / GPIO | [`Motor`] |
//! | right motor PWM / dir | PB15 / PB13 | TIM12 CH2 at 20 kHz / GPIO | [`Motor`] (mirrored) |
//! | left encoder A / B | PA6 / PA7 | TIM3 CH1 / CH2, encoder mode | [`WheelEncoder`] |
//! | right encoder A / B | PB6 / PB7 | TIM4 CH1 / CH2, encoder mode | [`WheelEncoder`] (mirrored) |
//! | emergency stop | PC11 | GPIO input, pull-up, pressed or broken = high | [`EmergencyStop`] |
//! | battery voltage | PC0 | ADC1 IN10, through a 47 kΩ / 10 kΩ divider | [`BatteryMonitor`] |
//! | delays | — | TIM6 (top sonar), TIM7 (bottom sonar), TIM13 (neck), 1 MHz | [`UsDelay`] |
//!
//! The two sonars follow the seed's robot (`tsonar`, `bsonar`); the pins are 3.3 V: 5 V sensors
//! (HC-SR04 echo, 5 V encoders) need a divider or level shifter.
//!
//! HAL: stm32f4xx-hal 0.23. Its timer `Delay::delay_ns` waits `ns` *microseconds*, so the
//! delays are wrapped in [`UsDelay`], which rounds nanoseconds up to whole microseconds.

use cortex_m::peripheral::{DCB, DWT};
use stm32f4xx_hal::{
    adc::{
        config::{AdcConfig, SampleTime},
        Adc,
    },
    gpio::{self, Analog, Input, Output, PushPull},
    pac,
    prelude::*,
    qei::Qei,
    rcc::Rcc,
    timer::{
        CaptureChannel, CaptureExt, CaptureHzManager, CapturePolarity, DelayUs, Flag, PwmChannel,
        PwmHzManager, C1, C2,
    },
};
use twil_core::drivers::motor::battery_v_from_pin_mv;
use twil_core::drivers::neck_stepper::NeckGeometry;
use twil_core::drivers::wheel_encoder::max_counts_per_period;
use twil_core::drivers::{
    ActiveLevel, EchoCapture, EchoEdge, EmergencyStop, Motor, Mounting, NeckStepper, QuadratureCounter,
    SonarRanger, SonarWindow, WheelEncoder,
};
use twil_core::robot::RobotConfig;

/// Tick rate of the echo captures, Hz (1 µs = 0.17 mm of range).
pub const ECHO_TICK_HZ: u32 = 1_000_000;
/// Motor PWM frequency, Hz: above hearing, within the bridges' 20 kHz limit.
pub const MOTOR_PWM_HZ: u32 = 20_000;
/// Battery divider: battery volts per pin volt ((47 kΩ + 10 kΩ) / 10 kΩ): 15 V → 2.63 V.
pub const BATTERY_DIVIDER_RATIO: f32 = 5.7;
/// Core clock, Hz (`main.rs` sets the PLL to it): DWT cycles per second for echo time-outs.
pub const SYSCLK_HZ: u32 = 168_000_000;

/// A timer-based delay whose `delay_ns` really waits nanoseconds (rounded up to microseconds).
pub struct UsDelay<TIM>(DelayUs<TIM>);

impl<TIM: stm32f4xx_hal::timer::Instance> embedded_hal::delay::DelayNs for UsDelay<TIM> {
    fn delay_ns(&mut self, ns: u32) {
        self.0.delay_us(ns.div_ceil(1_000));
    }
    fn delay_us(&mut self, us: u32) {
        self.0.delay_us(us);
    }
    fn delay_ms(&mut self, ms: u32) {
        self.0.delay_ms(ms);
    }
}

macro_rules! timer_echo {
    ($name:ident, $TIM:ty, $C:expr, $flag:expr, $pin_bit:expr) => {
        /// An echo line on a timer channel in input capture on both edges; the polarity of an
        /// edge is the pin's level read right after its capture (GPIOA IDR). Edge times count
        /// from the timer's counter at [`arm`](EchoCapture::arm); the time-out counts DWT
        /// cycles.
        pub struct $name {
            manager: CaptureHzManager<$TIM>,
            channel: CaptureChannel<$TIM, { $C }>,
            armed_at_cycles: u32,
            armed_at_count: u32,
        }

        impl $name {
            fn counter() -> u32 {
                // SAFETY: a read of the timer's counter register, which nothing else writes.
                unsafe { (*<$TIM>::ptr()).cnt().read().bits() }
            }
            fn pin_high() -> bool {
                // SAFETY: a read of GPIOA's input data register (read-only).
                unsafe { (*pac::GPIOA::ptr()).idr().read().bits() & (1 << $pin_bit) != 0 }
            }
        }

        impl EchoCapture for $name {
            fn tick_hz(&self) -> u32 {
                ECHO_TICK_HZ
            }

            fn arm(&mut self) {
                // Reading the capture register clears its flag; an overcapture is cleared too.
                let _ = self.channel.get_capture();
                self.manager.clear_all_flags();
                self.armed_at_cycles = DWT::cycle_count();
                self.armed_at_count = Self::counter();
            }

            fn next_edge(&mut self, deadline_ticks: u32) -> Option<EchoEdge> {
                loop {
                    if self.manager.flags().contains($flag) {
                        let at = self.channel.get_capture();
                        return Some(EchoEdge {
                            rising: Self::pin_high(),
                            at_ticks: at.wrapping_sub(self.armed_at_count),
                        });
                    }
                    if self.elapsed_ticks() > deadline_ticks {
                        return None;
                    }
                }
            }

            fn elapsed_ticks(&mut self) -> u32 {
                DWT::cycle_count().wrapping_sub(self.armed_at_cycles) / (SYSCLK_HZ / ECHO_TICK_HZ)
            }
        }
    };
}
timer_echo!(EchoTim5Ch2, pac::TIM5, C2, Flag::C2, 1);
timer_echo!(EchoTim2Ch1, pac::TIM2, C1, Flag::C1, 5);

/// A timer in encoder mode (×4: both edges of both channels) as a [`QuadratureCounter`].
pub struct WheelCounter<TIM: stm32f4xx_hal::qei::Instance>(Qei<TIM>);

macro_rules! wheel_counter {
    ($TIM:ty) => {
        impl QuadratureCounter for WheelCounter<$TIM> {
            fn count(&mut self) -> u16 {
                // TIM3 and TIM4 are 16-bit: the count is the raw register.
                self.0.count()
            }
        }
    };
}
wheel_counter!(pac::TIM3);
wheel_counter!(pac::TIM4);

/// The battery voltage, read on ADC1 through the divider.
pub struct BatteryMonitor {
    adc: Adc<pac::ADC1>,
    pin: gpio::PC0<Analog>,
}

impl BatteryMonitor {
    /// One conversion (480 cycles: the divider's source impedance needs a long sample), volts.
    pub fn read_battery_v(&mut self) -> f32 {
        let sample = self.adc.convert(&self.pin, SampleTime::Cycles_480);
        battery_v_from_pin_mv(self.adc.sample_to_millivolts(sample), BATTERY_DIVIDER_RATIO)
    }
}

type Out<const P: char, const N: u8> = gpio::Pin<P, N, Output<PushPull>>;
type In<const P: char, const N: u8> = gpio::Pin<P, N, Input>;

/// The top sonar.
pub type SonarTop = SonarRanger<Out<'B', 0>, EchoTim5Ch2, UsDelay<pac::TIM6>>;
/// The bottom sonar.
pub type SonarBottom = SonarRanger<Out<'B', 1>, EchoTim2Ch1, UsDelay<pac::TIM7>>;
/// The neck.
pub type Neck = NeckStepper<Out<'C', 8>, Out<'C', 9>, In<'C', 10>, UsDelay<pac::TIM13>>;
/// The left motor.
pub type MotorLeft = Motor<PwmChannel<pac::TIM12, C1>, Out<'B', 12>>;
/// The right motor.
pub type MotorRight = Motor<PwmChannel<pac::TIM12, C2>, Out<'B', 13>>;

/// Everything the board module wires, by name.
pub struct Board {
    /// Top sonar (full sweeps in the seed).
    pub sonar_top: SonarTop,
    /// Bottom sonar (normal sweeps in the seed).
    // The seed's second sonar: wired and built, not used by the mission yet (one sweeping
    // sonar, as the simulator's).
    #[allow(dead_code)]
    pub sonar_bottom: SonarBottom,
    /// The sonar neck (not homed yet).
    pub neck: Neck,
    /// Left wheel motor (stopped).
    pub motor_left: MotorLeft,
    /// Right wheel motor (stopped, mirrored).
    pub motor_right: MotorRight,
    /// Left wheel encoder.
    pub wheel_left: WheelEncoder<WheelCounter<pac::TIM3>>,
    /// Right wheel encoder (mirrored).
    pub wheel_right: WheelEncoder<WheelCounter<pac::TIM4>>,
    /// Emergency stop (latched until cleared).
    pub estop: EmergencyStop<In<'C', 11>>,
    /// Battery voltage.
    pub battery: BatteryMonitor,
    /// The PWM timer; kept so that it is never reconfigured behind the motors' back.
    #[allow(dead_code)]
    pub pwm_timer: PwmHzManager<pac::TIM12>,
}

/// The peripherals and pins the board uses (USART1, PA9 and PA10 stay with `main.rs`).
pub struct BoardParts {
    /// Timers: echo captures, encoders, delays, PWM.
    pub tim2: pac::TIM2,
    pub tim3: pac::TIM3,
    pub tim4: pac::TIM4,
    pub tim5: pac::TIM5,
    pub tim6: pac::TIM6,
    pub tim7: pac::TIM7,
    pub tim12: pac::TIM12,
    pub tim13: pac::TIM13,
    /// The battery ADC.
    pub adc1: pac::ADC1,
    /// Pins, as the GPIO split hands them out.
    pub pa1: gpio::PA1,
    pub pa5: gpio::PA5,
    pub pa6: gpio::PA6,
    pub pa7: gpio::PA7,
    pub pb0: gpio::PB0,
    pub pb1: gpio::PB1,
    pub pb6: gpio::PB6,
    pub pb7: gpio::PB7,
    pub pb12: gpio::PB12,
    pub pb13: gpio::PB13,
    pub pb14: gpio::PB14,
    pub pb15: gpio::PB15,
    pub pc0: gpio::PC0,
    pub pc8: gpio::PC8,
    pub pc9: gpio::PC9,
    pub pc10: gpio::PC10,
    pub pc11: gpio::PC11,
}

/// Configure every peripheral of the table above and build the drivers: motors stopped, neck
/// not homed, emergency stop latched. Needs the clocks frozen at [`SYSCLK_HZ`].
pub fn take(
    parts: BoardParts,
    rcc: &mut Rcc,
    dcb: &mut DCB,
    dwt: &mut DWT,
    config: &RobotConfig,
) -> Board {
    // The echo time-outs count core cycles.
    dcb.enable_trace();
    dwt.enable_cycle_counter();

    let window = SonarWindow::from_config(config);
    let (top_manager, (_, top_ch, ..)) = parts.tim5.capture_hz(ECHO_TICK_HZ.Hz(), rcc);
    let mut top_ch = top_ch.with(parts.pa1);
    top_ch.set_polarity(CapturePolarity::ActiveBoth);
    top_ch.enable();
    let (bottom_manager, (bottom_ch, ..)) = parts.tim2.capture_hz(ECHO_TICK_HZ.Hz(), rcc);
    let mut bottom_ch = bottom_ch.with(parts.pa5);
    bottom_ch.set_polarity(CapturePolarity::ActiveBoth);
    bottom_ch.enable();
    let sonar_top = SonarRanger::new(
        parts.pb0.into_push_pull_output(),
        EchoTim5Ch2 {
            manager: top_manager,
            channel: top_ch,
            armed_at_cycles: 0,
            armed_at_count: 0,
        },
        UsDelay(parts.tim6.delay_us(rcc)),
        window,
    );
    let sonar_bottom = SonarRanger::new(
        parts.pb1.into_push_pull_output(),
        EchoTim2Ch1 {
            manager: bottom_manager,
            channel: bottom_ch,
            armed_at_cycles: 0,
            armed_at_count: 0,
        },
        UsDelay(parts.tim7.delay_us(rcc)),
        window,
    );

    let neck = NeckStepper::new(
        parts.pc8.into_push_pull_output(),
        parts.pc9.into_push_pull_output(),
        parts.pc10.into_pull_up_input(),
        UsDelay(parts.tim13.delay_us(rcc)),
        NeckGeometry::from_config(config),
    );

    let (pwm_timer, (left_pwm, right_pwm)) = parts.tim12.pwm_hz(MOTOR_PWM_HZ.Hz(), rcc);
    let mut left_pwm = left_pwm.with(parts.pb14);
    let mut right_pwm = right_pwm.with(parts.pb15);
    left_pwm.set_duty(0);
    right_pwm.set_duty(0);
    left_pwm.enable();
    right_pwm.enable();
    let mut motor_left = Motor::new(
        left_pwm,
        parts.pb12.into_push_pull_output(),
        config.max_voltage_v,
        true,
    );
    let mut motor_right = Motor::new(
        right_pwm,
        parts.pb13.into_push_pull_output(),
        config.max_voltage_v,
        false,
    );
    // Duty 0 cannot fail on this HAL (its PWM error type is `Infallible`).
    let _ = motor_left.stop();
    let _ = motor_right.stop();

    let limit = max_counts_per_period(config);
    let wheel_left = WheelEncoder::new(
        WheelCounter(Qei::new(parts.tim3, (parts.pa6, parts.pa7), rcc)),
        Mounting::Normal,
        limit,
    );
    let wheel_right = WheelEncoder::new(
        WheelCounter(Qei::new(parts.tim4, (parts.pb6, parts.pb7), rcc)),
        Mounting::Mirrored,
        limit,
    );

    let estop = EmergencyStop::new(parts.pc11.into_pull_up_input(), ActiveLevel::High);

    let battery = BatteryMonitor {
        adc: Adc::new(parts.adc1, true, AdcConfig::default(), rcc),
        pin: parts.pc0.into_analog(),
    };

    Board {
        sonar_top,
        sonar_bottom,
        neck,
        motor_left,
        motor_right,
        wheel_left,
        wheel_right,
        estop,
        battery,
        pwm_timer,
    }
}
