//! The board: Twil's signals on an **Olimex STM32-H405** (STM32F405RGT6, 8 MHz crystal, port
//! pins on headers; its own LED is PC12, its button PA0, USB PA11/PA12 with VBUS sensing on
//! PC4 and the USB pull-up switched by PC11 ("USB DISC" in the board files), debug PA13/PA14
//! (and PA15/PB3/PB4 for JTAG): none of them is used here). Wiring only: every rule about the
//! signals lives in `twil_core::drivers`; docs/firmware.md has the wiring table with the
//! dividers, pull-ups and pull-downs each signal needs.
//!
//! | signal | pin | peripheral | driver |
//! |---|---|---|---|
//! | host link TX / RX | PA9 / PA10 | USART1 (in `main.rs`) | `link::Device` |
//! | top sonar trigger | PB0 | GPIO push-pull | `body::Head` |
//! | top sonar echo | PA1 (an ADC pin, TTa: 3.3 V only; divider) | TIM5: CH2 captures the rise, CH1 (on TI2) the fall, 1 MHz, 3 µs filter | [`EchoLatchTim5`] |
//! | bottom sonar trigger | PB1 | GPIO push-pull | (wired, not used) |
//! | bottom sonar echo | PA5 (TTa; divider) | TIM2: CH1 the rise, CH2 (on TI1) the fall | [`EchoLatchTim2`] |
//! | neck step / dir | PC8 / PC9 | GPIO push-pull | `body::Head` |
//! | neck home switch | PC10 | GPIO input, pull-up, closed = low | `body::Head` |
//! | left motor PWM / dir | PB14 / PB12 | TIM12 CH1 at 20 kHz / GPIO | [`Motor`] |
//! | right motor PWM / dir | PB15 / PB13 | TIM12 CH2 at 20 kHz / GPIO | [`Motor`] (mirrored) |
//! | left encoder A / B | PA6 / PA7 (TTa) | TIM3 CH1 / CH2, encoder mode, pull-ups, 3 µs filter | [`WheelEncoder`] |
//! | right encoder A / B | PB6 / PB7 | TIM4 CH1 / CH2, encoder mode, pull-ups, 3 µs filter | [`WheelEncoder`] (mirrored) |
//! | emergency stop | PB5 | GPIO input, pull-up, pressed or broken = high | [`EmergencyStop`] |
//! | battery voltage | PC0 | ADC1 IN10 at 21 MHz, through a 47 kΩ / 10 kΩ divider | [`BatteryMonitor`] |
//!
//! The emergency stop was on PC11 until the H405's board files (NuttX, ChibiOS, Zephyr) showed
//! PC11 is its USB disconnect line; PB5 is free on the board and on its headers.
//!
//! HAL: stm32f4xx-hal 0.23. Register set-ups the HAL does not offer (a capture channel fed by
//! the other channel's input, input filters on the encoder timers, the HSE's start-up bound)
//! are written with the PAC, each with its RM0090 register named.

use stm32f4xx_hal::{
    adc::{
        config::{AdcConfig, Clock as AdcClock, SampleTime, Sequence},
        Adc,
    },
    gpio::{self, Analog, Input, Output, PushPull},
    pac,
    prelude::*,
    qei::Qei,
    rcc::{self, Rcc},
    timer::{
        CaptureChannel, CaptureExt, CaptureFilter, CaptureHzManager, CapturePolarity, PwmChannel,
        C1, C2,
    },
};
use twil_core::drivers::echo::latched_edges;
use twil_core::drivers::motor::battery_v_from_pin_mv;
use twil_core::drivers::neck_stepper::NeckGeometry;
use twil_core::drivers::wheel_encoder::max_counts_per_period;
use twil_core::drivers::{
    ActiveLevel, BatteryReadError, BatterySensor, Chassis, EchoCapture, EchoEdge, EmergencyStop,
    Motor, Mounting, NeckStepper, QuadratureCounter, SonarHead, SonarRanger, SonarWindow,
    WheelEncoder,
};
use twil_core::robot::RobotConfig;

/// Tick rate of the echo captures, Hz (1 µs = 0.17 mm of range).
pub const ECHO_TICK_HZ: u32 = 1_000_000;
/// Motor PWM frequency, Hz: above hearing, within the bridges' 20 kHz limit.
pub const MOTOR_PWM_HZ: u32 = 20_000;
/// Battery divider: battery volts per pin volt ((47 kΩ + 10 kΩ) / 10 kΩ): 15 V → 2.63 V.
pub const BATTERY_DIVIDER_RATIO: f32 = 5.7;
/// Core clock, Hz (the PLL, from the crystal or the HSI): the cycles of the short pulses.
pub const SYSCLK_HZ: u32 = 168_000_000;
/// The H405's crystal, Hz.
pub const HSE_HZ: u32 = 8_000_000;
/// How long the crystal may take to start, µs: DS8626 gives 2 ms typical (tSU(HSE)); ST's
/// own HAL waits 100 ms (`HSE_STARTUP_TIMEOUT`) before it calls the crystal dead.
pub const HSE_STARTUP_LIMIT_US: u32 = 100_000;
/// APB2 (PCLK2) at 168 MHz: 84 MHz (DS8626: at most 84 MHz).
pub const PCLK2_HZ: u32 = 84_000_000;
/// ADC clock, Hz: PCLK2 / 4. DS8626 (table "ADC characteristics"): fADC at most 36 MHz at
/// VDDA 2.4 … 3.6 V; the HAL's default, PCLK2 / 2 = 42 MHz, is above it.
pub const ADC_CLOCK_HZ: u32 = PCLK2_HZ / 4;
/// Input filter of the echo and encoder timers (RM0090, TIMx_CCMR1 ICxF = 0b1111): sampled at
/// fDTS / 32 = 2.6 MHz, 8 equal samples, so a level must hold 3.0 µs to count. It rejects the
/// 20 kHz PWM's switching spikes (tens to hundreds of ns); the encoders' fastest edges are
/// 335 µs apart (9.36 rad/s × 2000 counts per turn), an echo's two edges are delayed alike.
pub const INPUT_FILTER: CaptureFilter = CaptureFilter::FdtsDiv32N8;
/// [`INPUT_FILTER`]'s 4-bit ICxF value, for the encoder timers (the HAL's encoder set-up has
/// no filter).
const INPUT_FILTER_BITS: u32 = 0b1111;

// The clock tree the constants above assume, checked at compile time.
const _: () = assert!(ADC_CLOCK_HZ <= 36_000_000);
const _: () = assert!(SYSCLK_HZ / 2 == PCLK2_HZ);

/// Where the system clock comes from.
#[derive(Clone, Copy, Debug, PartialEq, Eq, defmt::Format)]
pub enum ClockSource {
    /// The 8 MHz crystal, ready after about this many µs.
    Crystal {
        /// Start-up time measured in 100 µs steps.
        startup_us: u32,
    },
    /// The crystal did not start within [`HSE_STARTUP_LIMIT_US`]: the HSI (±1 % at 25 °C,
    /// several % over temperature: sonar ranges and times scale with it; USB impossible).
    InternalFallback,
}

/// Start the crystal (bounded wait), then the PLL at [`SYSCLK_HZ`] from it, APB1 42 MHz,
/// APB2 84 MHz, the 48 MHz clock for USB; the clock security system then watches the
/// crystal (a failure switches to the HSI and raises the NMI, see `main.rs`). Without a
/// crystal: the PLL from the HSI, same frequencies, and a logged warning.
pub fn start_clocks(rcc: Rcc) -> (Rcc, ClockSource) {
    // RM0090 RCC_CR: HSEON, then HSERDY. The HAL's `freeze` waits for HSERDY without a
    // bound, so a dead crystal would hang here: it is started and waited for first.
    rcc.cr().modify(|_, w| w.hseon().set_bit());
    const STEP_US: u32 = 100;
    let mut waited_us = 0;
    // Still on the 16 MHz HSI: `asm::delay` counts core cycles.
    while rcc.cr().read().hserdy().bit_is_clear() && waited_us < HSE_STARTUP_LIMIT_US {
        cortex_m::asm::delay(16 * STEP_US);
        waited_us += STEP_US;
    }
    if rcc.cr().read().hserdy().bit_is_set() {
        let rcc = rcc.freeze(
            rcc::Config::hse(HSE_HZ.Hz())
                .sysclk(SYSCLK_HZ.Hz())
                .require_pll48clk(),
        );
        // RM0090 RCC_CR CSSON: a crystal that stops switches the core to the HSI and raises
        // the NMI (`main.rs` zeroes the motors and resets then).
        rcc.cr().modify(|_, w| w.csson().set_bit());
        (
            rcc,
            ClockSource::Crystal {
                startup_us: waited_us,
            },
        )
    } else {
        rcc.cr().modify(|_, w| w.hseon().clear_bit());
        (
            rcc.freeze(rcc::Config::hsi().sysclk(SYSCLK_HZ.Hz())),
            ClockSource::InternalFallback,
        )
    }
}

/// Log the clock tree (bring-up step 2).
pub fn log_clocks(rcc: &Rcc, source: ClockSource) {
    let c = &rcc.clocks;
    match source {
        ClockSource::Crystal { startup_us } => defmt::info!(
            "bring-up 2: clock: 8 MHz crystal ready after {} us; SYSCLK {} Hz, APB1 {} Hz, APB2 {} Hz, ADC {} Hz, USB {} Hz",
            startup_us,
            c.sysclk().raw(),
            c.pclk1().raw(),
            c.pclk2().raw(),
            c.pclk2().raw() / 4,
            c.pll48clk().map(|f| f.raw()).unwrap_or(0)
        ),
        ClockSource::InternalFallback => defmt::warn!(
            "bring-up 2: clock: the 8 MHz crystal did not start in {} us: running on the HSI (+-1 %), SYSCLK {} Hz",
            HSE_STARTUP_LIMIT_US,
            c.sysclk().raw()
        ),
    }
}

type Out<const P: char, const N: u8> = gpio::Pin<P, N, Output<PushPull>>;
type In<const P: char, const N: u8> = gpio::Pin<P, N, Input>;

/// The four motor-bridge inputs, driven low: what `init` does first.
pub struct MotorPins {
    /// Left direction (PB12).
    pub dir_left: Out<'B', 12>,
    /// Right direction (PB13).
    pub dir_right: Out<'B', 13>,
    /// Left PWM (PB14), low until TIM12 takes it.
    pub pwm_left: Out<'B', 14>,
    /// Right PWM (PB15), low until TIM12 takes it.
    pub pwm_right: Out<'B', 15>,
}

impl MotorPins {
    /// Drive the four pins low (push-pull outputs, low level written before the mode).
    pub fn low(pb12: gpio::PB12, pb13: gpio::PB13, pb14: gpio::PB14, pb15: gpio::PB15) -> Self {
        Self {
            dir_left: pb12.into_push_pull_output_in_state(gpio::PinState::Low),
            dir_right: pb13.into_push_pull_output_in_state(gpio::PinState::Low),
            pwm_left: pb14.into_push_pull_output_in_state(gpio::PinState::Low),
            pwm_right: pb15.into_push_pull_output_in_state(gpio::PinState::Low),
        }
    }
}

/// The port B pins the board uses besides the motors' (split at the start of `init`).
pub struct PortBRest {
    pub pb0: gpio::PB0,
    pub pb1: gpio::PB1,
    pub pb5: gpio::PB5,
    pub pb6: gpio::PB6,
    pub pb7: gpio::PB7,
}

macro_rules! echo_latch {
    ($name:ident, $TIM:ty, $C:ty, $rise_bit:expr, $fall_bit:expr, $rise_ccr:expr, $fall_ccr:expr) => {
        /// An echo pulse latched by two capture channels of one 32-bit timer on the same input
        /// (RM0090 §18.3.6, the PWM-input arrangement without the slave reset): one captures
        /// the rising edge, the other the falling one, so both times wait in the timer until
        /// the sonar task reads them after its `Mono::delay`. No interrupt, no busy wait.
        pub struct $name {
            _manager: CaptureHzManager<$TIM>,
            _direct: CaptureChannel<$TIM, $C>,
            /// The counter at `arm`: time 0 of the edges.
            armed_at: u32,
            /// The latched edges not handed out yet (read once, after the listen time).
            pending: [Option<EchoEdge>; 2],
        }

        impl EchoCapture for $name {
            fn tick_hz(&self) -> u32 {
                ECHO_TICK_HZ
            }

            fn arm(&mut self) {
                self.clear();
                self.armed_at = Self::regs().cnt().read().bits();
                self.pending = [None, None];
            }

            /// Never waits: called after the listen time, it hands out the latched rise and
            /// fall in time order (the latest of each, if more came: counted).
            fn next_edge(&mut self, deadline_ticks: u32) -> Option<EchoEdge> {
                if self.pending == [None, None] {
                    let edges = self.edges();
                    if edges.extra {
                        // Noise the 3 µs filter let through, or a line still high at the
                        // trigger: the decoder gets the latest edge of each kind.
                        defmt::warn!("echo: more edges than the latch holds: {}", edges);
                    }
                    self.pending = latched_edges(self.armed_at, edges.rise, edges.fall);
                }
                let next = self.pending.iter_mut().find(|e| e.is_some())?;
                let edge = (*next)?;
                if edge.at_ticks > deadline_ticks {
                    return None;
                }
                *next = None;
                Some(edge)
            }

            fn elapsed_ticks(&mut self) -> u32 {
                Self::regs().cnt().read().bits().wrapping_sub(self.armed_at)
            }
        }

        impl $name {
            fn regs() -> &'static pac::tim2::RegisterBlock {
                // SAFETY: TIM2 and TIM5 share TIM2's register layout (the PAC gives TIM5 the
                // same register types); this latch owns the timer (its manager is held), and
                // only reads the captures and clears their flags.
                unsafe { &*(<$TIM>::ptr() as *const pac::tim2::RegisterBlock) }
            }

            fn new(manager: CaptureHzManager<$TIM>, direct: CaptureChannel<$TIM, $C>) -> Self {
                Self {
                    _manager: manager,
                    _direct: direct,
                    armed_at: 0,
                    pending: [None, None],
                }
            }

            /// Forget earlier edges: clear the capture and overcapture flags (TIMx_SR, write 0
            /// to clear) and read both captures.
            fn clear(&mut self) {
                let r = Self::regs();
                let _ = r.ccr($rise_ccr).read().bits();
                let _ = r.ccr($fall_ccr).read().bits();
                r.sr().write(|w| unsafe { w.bits(!SR_CAPTURE_FLAGS) });
            }

            /// The latched edges since the last `arm`.
            pub fn edges(&mut self) -> EchoEdges {
                let r = Self::regs();
                let sr = r.sr().read().bits();
                let rise = (sr & (1 << $rise_bit) != 0).then(|| r.ccr($rise_ccr).read().bits());
                let fall = (sr & (1 << $fall_bit) != 0).then(|| r.ccr($fall_ccr).read().bits());
                // CCxOF (bit CCxIF + 8): an edge came while the previous one was unread.
                let extra = sr & ((1 << ($rise_bit + 8)) | (1 << ($fall_bit + 8))) != 0;
                EchoEdges { rise, fall, extra }
            }
        }
    };
}

/// TIMx_SR: CC1IF, CC2IF, CC1OF, CC2OF.
const SR_CAPTURE_FLAGS: u32 = (1 << 1) | (1 << 2) | (1 << 9) | (1 << 10);

// TIM5: PA1 is CH2 (TI2). CH2 captures TI2's rise (CCR2), CH1 (CC1S = 0b10: TI2) its fall (CCR1).
echo_latch!(EchoLatchTim5, pac::TIM5, C2, 2, 1, 1, 0);
// TIM2: PA5 is CH1 (TI1). CH1 captures TI1's rise (CCR1), CH2 (CC2S = 0b10: TI1) its fall (CCR2).
echo_latch!(EchoLatchTim2, pac::TIM2, C1, 1, 2, 0, 1);

/// The edges an echo latch holds (timer counts).
#[derive(Clone, Copy, Debug, PartialEq, Eq, defmt::Format)]
pub struct EchoEdges {
    /// Timer ticks at the rising edge, if one came.
    pub rise: Option<u32>,
    /// Timer ticks at the falling edge, if one came.
    pub fall: Option<u32>,
    /// More than one edge of a kind came (noise, or an echo line already high at the
    /// trigger): only the latest of each is held.
    pub extra: bool,
}

/// Put the companion channel (0 = CH1, 1 = CH2) of an echo latch on the other channel's
/// input, falling edge, enabled. That input's filter is the direct channel's (RM0090: ICxF
/// filters TIx, which both channels then see). RM0090 TIMx_CCMR1: CCxS = 0b10 selects the
/// other channel's input (written while CCxE = 0); TIMx_CCER: CCxP = 1, CCxNP = 0 is the
/// falling edge, CCxE enables the capture.
fn companion_falling(regs: &pac::tim2::RegisterBlock, companion: u8) {
    let shift = 8 * u32::from(companion);
    regs.ccmr1_input().modify(|r, w| unsafe {
        let mut bits = r.bits();
        bits &= !(0b11 << shift);
        bits |= 0b10 << shift;
        w.bits(bits)
    });
    let ccer = 4 * u32::from(companion);
    regs.ccer().modify(|r, w| unsafe {
        let mut bits = r.bits();
        bits &= !(0b1010 << ccer);
        bits |= (0b0010 | 0b0001) << ccer;
        w.bits(bits)
    });
}

/// A timer in encoder mode (×4: both edges of both channels) as a [`QuadratureCounter`].
pub struct WheelCounter<TIM: stm32f4xx_hal::qei::Instance>(Qei<TIM>);

macro_rules! wheel_counter {
    ($TIM:ty, $filtered:ident) => {
        impl QuadratureCounter for WheelCounter<$TIM> {
            fn count(&mut self) -> u16 {
                // TIM3 and TIM4 are 16-bit: the count is the raw register.
                self.0.count()
            }
        }

        impl WheelCounter<$TIM> {
            /// The encoder timer with [`INPUT_FILTER`] on both inputs (RM0090 TIMx_CCMR1 IC1F,
            /// IC2F; the HAL's encoder set-up leaves them at 0, no filter).
            fn $filtered(qei: Qei<$TIM>) -> Self {
                // SAFETY: the Qei owns the timer; this only sets the two filter fields, which
                // the encoder mode reads and nothing else writes.
                let regs = unsafe { &*<$TIM>::ptr() };
                regs.ccmr1_input().modify(|r, w| unsafe {
                    w.bits(r.bits() | (INPUT_FILTER_BITS << 4) | (INPUT_FILTER_BITS << 12))
                });
                Self(qei)
            }
        }
    };
}
wheel_counter!(pac::TIM3, filtered_tim3);
wheel_counter!(pac::TIM4, filtered_tim4);

/// The battery voltage, read on ADC1 through the divider without waiting: each call reads the
/// conversion the previous call started (50 ms earlier, one control period; a conversion takes
/// 23 µs) and starts the next. A conversion not done by then (ADC_SR EOC clear: the ADC
/// stopped) is a [`BatteryReadError`], which the chassis turns into a sensor fault.
pub struct BatteryMonitor {
    adc: Adc<pac::ADC1>,
    _pin: gpio::PC0<Analog>,
}

impl BatteryMonitor {
    /// 480 sample cycles: the divider's 8.2 kΩ source impedance needs a long sample (DS8626,
    /// "RAIN max" table: 480 cycles allow up to 50 kΩ at 12 bits).
    pub const SAMPLE: SampleTime = SampleTime::Cycles_480;

    fn new(adc1: pac::ADC1, pin: gpio::PC0, rcc: &mut Rcc) -> Self {
        let config = AdcConfig::default().clock(AdcClock::Pclk2_div_4);
        let mut adc = Adc::new(adc1, true, config, rcc);
        let pin = pin.into_analog();
        adc.configure_channel(&pin, Sequence::One, Self::SAMPLE);
        adc.start_conversion();
        Self { adc, _pin: pin }
    }
}

impl BatterySensor for BatteryMonitor {
    /// The last conversion in volts at the battery, and the next one started.
    fn read_battery_v(&mut self) -> Result<f32, BatteryReadError> {
        // SAFETY: a read of ADC1's status register (the conversion's end flag); the reading
        // of the data register below clears it, as RM0090 says.
        let done = unsafe { (*pac::ADC1::ptr()).sr().read().eoc().bit_is_set() };
        let sample = self.adc.current_sample();
        self.adc.start_conversion();
        if !done {
            return Err(BatteryReadError);
        }
        Ok(battery_v_from_pin_mv(
            self.adc.sample_to_millivolts(sample),
            BATTERY_DIVIDER_RATIO,
        ))
    }
}

/// A delay that waits in a loop, for the drivers' sub-10 µs waits only (the trigger pulse,
/// the step pulse, the direction set-up): everything longer is a `Mono` delay in the sonar
/// task. Counts core cycles at [`SYSCLK_HZ`].
pub struct SpinDelay;

impl embedded_hal::delay::DelayNs for SpinDelay {
    fn delay_ns(&mut self, ns: u32) {
        cortex_m::asm::delay(ns.div_ceil(1_000).saturating_mul(SYSCLK_HZ / 1_000_000));
    }
}

/// The wheels, the e-stop and the battery (`twil_core::drivers::body::Chassis`).
pub type BoardChassis = Chassis<
    PwmChannel<pac::TIM12, C1>,
    Out<'B', 12>,
    PwmChannel<pac::TIM12, C2>,
    Out<'B', 13>,
    WheelCounter<pac::TIM3>,
    WheelCounter<pac::TIM4>,
    In<'B', 5>,
    BatteryMonitor,
>;

/// The top sonar on the neck (`twil_core::drivers::body::SonarHead`).
pub type BoardHead = SonarHead<
    Out<'B', 0>,
    EchoLatchTim5,
    SpinDelay,
    Out<'C', 8>,
    Out<'C', 9>,
    In<'C', 10>,
    SpinDelay,
>;

/// Everything the board module wires, by name.
pub struct Board {
    /// The wheels (motors stopped, disarmed), the e-stop (latched), the battery.
    pub chassis: BoardChassis,
    /// The sonar head (the neck not homed).
    pub head: BoardHead,
    /// Bottom sonar (the seed's second sonar): wired and set up, not used by the mission yet.
    #[allow(dead_code)]
    pub bottom_sonar: (Out<'B', 1>, EchoLatchTim2),
    /// The PWM timer; kept so that it is never reconfigured behind the motors' back.
    #[allow(dead_code)]
    pub pwm_timer: stm32f4xx_hal::timer::PwmHzManager<pac::TIM12>,
}

/// The peripherals and pins the board uses (USART1, PA9 and PA10 stay with `main.rs`).
pub struct BoardParts {
    /// Timers: echo captures, encoders, PWM.
    pub tim2: pac::TIM2,
    pub tim3: pac::TIM3,
    pub tim4: pac::TIM4,
    pub tim5: pac::TIM5,
    pub tim12: pac::TIM12,
    /// The battery ADC.
    pub adc1: pac::ADC1,
    /// The motor pins, already low.
    pub motor_pins: MotorPins,
    /// Pins, as the GPIO split hands them out.
    pub pa1: gpio::PA1,
    pub pa5: gpio::PA5,
    pub pa6: gpio::PA6,
    pub pa7: gpio::PA7,
    pub pb0: gpio::PB0,
    pub pb1: gpio::PB1,
    pub pb5: gpio::PB5,
    pub pb6: gpio::PB6,
    pub pb7: gpio::PB7,
    pub pc0: gpio::PC0,
    pub pc8: gpio::PC8,
    pub pc9: gpio::PC9,
    pub pc10: gpio::PC10,
}

/// Configure every peripheral of the table above and build the drivers: motors stopped, neck
/// not homed, emergency stop latched. Needs the clocks frozen at [`SYSCLK_HZ`]. Logs
/// bring-up step 4 (the set-ups, the first battery reading and the e-stop's level).
pub fn take(parts: BoardParts, rcc: &mut Rcc, config: &RobotConfig) -> Board {
    // Echo latches: the direct channel through the HAL (1 MHz, rising), the companion by hand.
    let (top_manager, (_, top_ch, ..)) = parts.tim5.capture_hz(ECHO_TICK_HZ.Hz(), rcc);
    let mut top_ch = top_ch.with(parts.pa1);
    top_ch.set_polarity(CapturePolarity::ActiveHigh);
    top_ch.set_filter(INPUT_FILTER);
    top_ch.enable();
    companion_falling(EchoLatchTim5::regs(), 0);
    let (bottom_manager, (bottom_ch, ..)) = parts.tim2.capture_hz(ECHO_TICK_HZ.Hz(), rcc);
    let mut bottom_ch = bottom_ch.with(parts.pa5);
    bottom_ch.set_polarity(CapturePolarity::ActiveHigh);
    bottom_ch.set_filter(INPUT_FILTER);
    bottom_ch.enable();
    companion_falling(EchoLatchTim2::regs(), 1);

    let window = SonarWindow::from_config(config);
    let sonar = SonarRanger::new(
        parts
            .pb0
            .into_push_pull_output_in_state(gpio::PinState::Low),
        EchoLatchTim5::new(top_manager, top_ch),
        SpinDelay,
        window,
    );
    let neck = NeckStepper::new(
        parts
            .pc8
            .into_push_pull_output_in_state(gpio::PinState::Low),
        parts
            .pc9
            .into_push_pull_output_in_state(gpio::PinState::Low),
        parts.pc10.into_pull_up_input(),
        SpinDelay,
        NeckGeometry::from_config(config),
    );
    let head = SonarHead::new(sonar, neck);
    let bottom_sonar = (
        parts
            .pb1
            .into_push_pull_output_in_state(gpio::PinState::Low),
        EchoLatchTim2::new(bottom_manager, bottom_ch),
    );

    let pins = parts.motor_pins;
    let (pwm_timer, (left_pwm, right_pwm)) = parts.tim12.pwm_hz(MOTOR_PWM_HZ.Hz(), rcc);
    let mut left_pwm = left_pwm.with(pins.pwm_left);
    let mut right_pwm = right_pwm.with(pins.pwm_right);
    left_pwm.set_duty(0);
    right_pwm.set_duty(0);
    left_pwm.enable();
    right_pwm.enable();
    let mut motor_left = Motor::new(left_pwm, pins.dir_left, config.max_voltage_v, true);
    let mut motor_right = Motor::new(right_pwm, pins.dir_right, config.max_voltage_v, false);
    // Duty 0 cannot fail on this HAL (its PWM error type is `Infallible`).
    let _ = motor_left.stop();
    let _ = motor_right.stop();

    let limit = max_counts_per_period(config);
    let left_pins = (
        parts.pa6.internal_pull_up(true),
        parts.pa7.internal_pull_up(true),
    );
    let right_pins = (
        parts.pb6.internal_pull_up(true),
        parts.pb7.internal_pull_up(true),
    );
    let wheel_left = WheelEncoder::new(
        WheelCounter::filtered_tim3(Qei::new(parts.tim3, left_pins, rcc)),
        Mounting::Normal,
        limit,
    );
    let wheel_right = WheelEncoder::new(
        WheelCounter::filtered_tim4(Qei::new(parts.tim4, right_pins, rcc)),
        Mounting::Mirrored,
        limit,
    );

    let estop_pin = parts.pb5.into_pull_up_input();
    let estop_pressed = estop_pin.is_high();
    let estop = EmergencyStop::new(estop_pin, ActiveLevel::High);

    let mut battery = BatteryMonitor::new(parts.adc1, parts.pc0, rcc);
    // The first conversion (started above) takes 23 µs: wait it out once, here in `init`.
    cortex_m::asm::delay(SYSCLK_HZ / 1_000_000 * 30);
    let battery_v = battery.read_battery_v();
    defmt::info!(
        "bring-up 4: board set up: PWM {} Hz on TIM12 (duty 0), encoders TIM3/TIM4, echo latches TIM5/TIM2 at {} Hz, ADC {} Hz; battery {} V; e-stop input {}",
        MOTOR_PWM_HZ,
        ECHO_TICK_HZ,
        ADC_CLOCK_HZ,
        battery_v,
        if estop_pressed { "pressed or open (latched)" } else { "released" }
    );
    let chassis = Chassis::new(
        motor_left,
        motor_right,
        wheel_left,
        wheel_right,
        estop,
        battery,
    );

    Board {
        chassis,
        head,
        bottom_sonar,
        pwm_timer,
    }
}
