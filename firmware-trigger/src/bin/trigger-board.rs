//! Trigger firmware for the Nucleo-F401RE (STM32F401RE, Cortex-M4F).
//!
//! Clock: HSE 8 MHz (on the Nucleo this is the ST-LINK's crystal-derived MCO fed to PH0, used in
//! bypass mode) -> PLL -> SYSCLK 84 MHz; APB1 42 MHz, so the APB1 timers count at 84 MHz.
//!
//! Pulses come from hardware timers, never software toggling:
//! - TIM2 (32-bit, master): depth-camera pulses, 30 Hz, PWM mode 1 on channel 1 -> **PA0**
//!   (Arduino A0, CN8 pin 1 / morpho CN7 pin 28), alternate function 1.
//! - TIM3 (16-bit, slave of TIM2 through internal trigger ITR1, trigger mode): event-camera
//!   pulses, 120 Hz, PWM mode 1 on channel 1 -> **PA6** (Arduino D12, CN5 pin 5 / morpho CN10
//!   pin 13), alternate function 2. The pulse coinciding with a TIM2 pulse is wider (phase code);
//!   the width for the next pulse is preloaded from TIM3's update interrupt.
//! - Setting TIM2's counter enable raises its TRGO (master mode "enable"), which starts TIM3 in
//!   the same few clock cycles: both count the same 6 MHz tick from the same instant, with
//!   periods of exactly 200 000 and 50 000 ticks, so they stay phase-locked indefinitely.
//! - **PA5** (LD2, the green user LED) is lit while the pulses run.
//! - USART2 on **PA2** (TX) / **PA3** (RX), alternate function 7, 115200 8N1: the ST-LINK's
//!   virtual COM port. Commands: `start`, `stop`, `status`, `rate [HZ]` (see `command`).
//!
//! Logs go out over RTT with `defmt` (`probe-rs run` prints them).
#![cfg_attr(target_os = "none", no_std)]
#![cfg_attr(target_os = "none", no_main)]

/// Host builds (e.g. `--all-features` on the workspace) get a stub that says where this runs.
#[cfg(not(target_os = "none"))]
fn main() {
    eprintln!(
        "trigger-board runs on the STM32F401: cargo run --release --target thumbv7em-none-eabihf --features board --bin trigger-board"
    );
    std::process::exit(2);
}

#[cfg(target_os = "none")]
mod firmware {
    use core::cell::RefCell;
    use core::sync::atomic::{AtomicU32, Ordering};

    use cortex_m::asm;
    use cortex_m::peripheral::NVIC;
    use cortex_m_rt::entry;
    use critical_section::Mutex;
    use defmt_rtt as _;
    use firmware_trigger::command::{
        Action, Command, LineBuffer, Reply, execute, refuse, refuse_no_plan,
    };
    use firmware_trigger::{
        BOARD_TIMER_CLOCK_HZ, DEFAULT_DEPTH_HZ, PulseTrain, PulseWidths, TimerPlan,
    };
    use heapless::Deque;
    use panic_probe as _;
    use stm32f4::stm32f401::{self as pac, Interrupt, interrupt};

    /// HSE input frequency, Hz: the ST-LINK MCO on a stock Nucleo-F401RE.
    const HSE_HZ: u32 = 8_000_000;
    /// HSE in bypass mode (external clock on PH0). Set false if crystal X3 is fitted.
    const HSE_BYPASS: bool = true;
    /// HSI frequency, Hz: what the MCU runs on if the HSE does not start.
    const HSI_HZ: u32 = 16_000_000;
    /// PLL: VCO input HSE / 4 = 2 MHz, VCO 2 MHz x 168 = 336 MHz, SYSCLK 336 / 4 = 84 MHz,
    /// 48 MHz domain 336 / 7.
    const PLL_M: u8 = 4;
    const PLL_N: u16 = 168;
    const PLL_Q: u8 = 7;
    /// UART baud rate.
    const BAUD: u32 = 115_200;
    /// Polls of a ready flag before giving up (bounded waits: the firmware never hangs).
    const SPIN_LIMIT: u32 = 2_000_000;
    /// Received bytes buffered between the UART interrupt and the command loop.
    const RX_CAPACITY: usize = 64;

    /// The generator's run state, shared by the command loop and TIM3's update interrupt.
    static TRAIN: Mutex<RefCell<Option<PulseTrain>>> = Mutex::new(RefCell::new(None));
    /// Bytes received by the UART interrupt, not yet parsed.
    static RX: Mutex<RefCell<Deque<u8, RX_CAPACITY>>> = Mutex::new(RefCell::new(Deque::new()));
    /// Received bytes lost (buffer full or UART overrun); reported, never silent.
    static RX_LOST: AtomicU32 = AtomicU32::new(0);

    /// Clock tree as configured.
    struct Clocks {
        /// APB1 peripheral clock (USART2), Hz.
        pclk1_hz: u32,
        /// APB1 timer clock (TIM2, TIM3), Hz.
        timer_hz: u32,
        /// True when running from the crystal through the PLL.
        crystal: bool,
    }

    #[entry]
    fn main() -> ! {
        let Some(dp) = pac::Peripherals::take() else {
            // Only possible if taken twice; nothing safe to do but halt.
            loop {
                asm::wfi();
            }
        };
        // Keep the debug port (RTT) alive while the core sleeps in WFI.
        dp.DBGMCU.cr().modify(|_, w| w.dbg_sleep().set_bit());

        let clocks = init_clocks(&dp);
        if clocks.crystal {
            defmt::info!(
                "clock: HSE {=u32} Hz -> SYSCLK 84 MHz, timers {=u32} Hz",
                HSE_HZ,
                clocks.timer_hz
            );
        } else {
            defmt::error!("HSE did not start: running on HSI, pulses refused (inexact clock)");
        }
        init_pins(&dp);
        init_uart(&dp, clocks.pclk1_hz);
        init_timers_idle(&dp);

        let plan = TimerPlan::new(clocks.timer_hz, DEFAULT_DEPTH_HZ, PulseWidths::default());
        let plan_error = match plan {
            Ok(plan) => {
                defmt::info!(
                    "plan: psc={=u16} depth_arr={=u32} event_arr={=u16} widths={=u32}/{=u16}/{=u16} ticks",
                    plan.prescaler(),
                    plan.depth_reload(),
                    plan.event_reload(),
                    plan.depth_width_ticks(),
                    plan.event_width_ticks(),
                    plan.event_coded_width_ticks()
                );
                critical_section::with(|cs| {
                    TRAIN.borrow_ref_mut(cs).replace(PulseTrain::new(plan));
                });
                None
            }
            Err(e) => {
                defmt::error!("no exact timer plan at {=u32} Hz", clocks.timer_hz);
                Some(e)
            }
        };
        debug_assert!(!clocks.crystal || clocks.timer_hz == BOARD_TIMER_CLOCK_HZ);

        // SAFETY: the handlers only touch state guarded by critical sections and the registers
        // of their own peripheral.
        unsafe {
            NVIC::unmask(Interrupt::TIM3);
            NVIC::unmask(Interrupt::USART2);
        }
        write_uart(&dp, b"trigger ready: start | stop | status | rate [HZ]\r\n");

        let mut lines = LineBuffer::new();
        let mut reported_lost = 0;
        loop {
            let byte = critical_section::with(|cs| {
                let byte = RX.borrow_ref_mut(cs).pop_front();
                if byte.is_none() {
                    // Sleep until the next interrupt; a pending one wakes WFI at once even with
                    // interrupts masked, so no byte can slip in between the check and the sleep.
                    asm::wfi();
                }
                byte
            });
            let lost = RX_LOST.load(Ordering::Relaxed);
            if lost != reported_lost {
                defmt::warn!("uart: {=u32} received bytes lost so far", lost);
                reported_lost = lost;
            }
            let Some(byte) = byte else { continue };
            let Some(outcome) = lines.push(byte) else {
                continue;
            };
            let mut reply = Reply::new();
            match (outcome, &plan_error) {
                (Err(e), _) => {
                    defmt::warn!("uart: refused a line");
                    refuse(&e, &mut reply);
                }
                (Ok(_), Some(e)) => refuse_no_plan(e, &mut reply),
                (Ok(cmd), None) => run_command(&dp, cmd, &mut reply),
            }
            write_uart(&dp, reply.as_bytes());
        }
    }

    /// Executes a command on the shared run state and performs its hardware action.
    fn run_command(dp: &pac::Peripherals, cmd: Command, reply: &mut Reply) {
        if cmd == Command::Stop {
            // Let the pulses in progress end first so no camera sees a cut-short pulse. Done
            // outside the critical section: the UART and TIM3 interrupts keep running.
            let plan =
                critical_section::with(|cs| TRAIN.borrow_ref(cs).as_ref().map(|t| *t.plan()));
            if let Some(plan) = plan {
                wait_outputs_low(dp, &plan);
            }
        }
        critical_section::with(|cs| {
            let mut guard = TRAIN.borrow_ref_mut(cs);
            let Some(train) = guard.as_mut() else {
                return;
            };
            match execute(cmd, train, reply) {
                Action::Start { first_width } => {
                    start_timers(dp, train.plan(), first_width);
                    defmt::info!(
                        "started at {=u32} Hz / {=u32} Hz",
                        train.plan().depth_hz(),
                        train.plan().event_hz()
                    );
                }
                Action::Stop => {
                    stop_timers(dp);
                    let counts = train.counts();
                    defmt::info!(
                        "stopped after {=u64} event / {=u64} depth pulses",
                        counts.event,
                        counts.depth
                    );
                }
                Action::None => {}
            }
        });
    }

    /// HSE (bypass) -> PLL -> 84 MHz SYSCLK. On HSE or PLL failure stays on HSI and says so.
    fn init_clocks(dp: &pac::Peripherals) -> Clocks {
        let rcc = &dp.RCC;
        let on_hsi = Clocks {
            pclk1_hz: HSI_HZ,
            timer_hz: HSI_HZ,
            crystal: false,
        };
        rcc.cr()
            .modify(|_, w| w.hsebyp().bit(HSE_BYPASS).hseon().set_bit());
        if !spin_until(|| rcc.cr().read().hserdy().bit_is_set()) {
            rcc.cr().modify(|_, w| w.hseon().clear_bit());
            return on_hsi;
        }
        // Voltage scale 2 allows 84 MHz; flash needs 2 wait states at 84 MHz and 2.7-3.6 V.
        rcc.apb1enr().modify(|_, w| w.pwren().set_bit());
        dp.PWR.cr().modify(|_, w| w.vos().scale2());
        dp.FLASH.acr().modify(|_, w| {
            w.latency().ws2();
            w.prften().set_bit();
            w.icen().set_bit();
            w.dcen().set_bit()
        });
        rcc.pllcfgr().write(|w| {
            w.pllsrc().hse();
            w.pllp().div4();
            // SAFETY: M = 4, N = 168, Q = 7 are within the fields' documented ranges
            // (2..=63, 50..=432, 2..=15).
            unsafe {
                w.pllm().bits(PLL_M);
                w.plln().bits(PLL_N);
                w.pllq().bits(PLL_Q)
            }
        });
        rcc.cr().modify(|_, w| w.pllon().set_bit());
        if !spin_until(|| rcc.cr().read().pllrdy().bit_is_set()) {
            return on_hsi;
        }
        rcc.cfgr().modify(|_, w| {
            w.hpre().div1();
            w.ppre1().div2();
            w.ppre2().div1();
            w.sw().pll()
        });
        if !spin_until(|| rcc.cfgr().read().sws().is_pll()) {
            return on_hsi;
        }
        let sysclk = HSE_HZ / u32::from(PLL_M) * u32::from(PLL_N) / 4;
        Clocks {
            pclk1_hz: sysclk / 2,
            // APB1 prescaler != 1, so the APB1 timers run at twice PCLK1.
            timer_hz: sysclk,
            crystal: true,
        }
    }

    /// PA0 = TIM2_CH1 (AF1), PA6 = TIM3_CH1 (AF2), PA2/PA3 = USART2 TX/RX (AF7), PA5 = LED.
    fn init_pins(dp: &pac::Peripherals) {
        dp.RCC.ahb1enr().modify(|_, w| w.gpioaen().set_bit());
        let gpioa = &dp.GPIOA;
        gpioa.bsrr().write(|w| w.br5().set_bit());
        gpioa.ospeedr().modify(|_, w| {
            w.ospeedr0().high_speed();
            w.ospeedr6().high_speed()
        });
        gpioa.afrl().modify(|_, w| {
            w.afrl0().af1();
            w.afrl2().af7();
            w.afrl3().af7();
            w.afrl6().af2()
        });
        gpioa.moder().modify(|_, w| {
            w.moder0().alternate();
            w.moder2().alternate();
            w.moder3().alternate();
            w.moder5().output();
            w.moder6().alternate()
        });
    }

    /// USART2, 8N1, receive interrupt on.
    fn init_uart(dp: &pac::Peripherals, pclk1_hz: u32) {
        dp.RCC.apb1enr().modify(|_, w| w.usart2en().set_bit());
        let usart = &dp.USART2;
        // Oversampling by 16: BRR holds PCLK / baud as 12.4 fixed point, rounded.
        let brr = u16::try_from((pclk1_hz + BAUD / 2) / BAUD).unwrap_or(u16::MAX);
        // SAFETY: any 16-bit value is a valid BRR; 42 MHz / 115200 gives 365.
        usart.brr().write(|w| unsafe { w.bits(brr) });
        usart.cr1().write(|w| {
            w.ue().set_bit();
            w.te().set_bit();
            w.re().set_bit();
            w.rxneie().set_bit()
        });
    }

    /// Enables both timers' clocks and drives both outputs low (forced inactive) until start.
    fn init_timers_idle(dp: &pac::Peripherals) {
        dp.RCC
            .apb1enr()
            .modify(|_, w| w.tim2en().set_bit().tim3en().set_bit());
        force_outputs_low(dp);
        dp.TIM2.ccer().modify(|_, w| w.cc1e().set_bit());
        dp.TIM3.ccer().modify(|_, w| w.cc1e().set_bit());
        // Master: TRGO follows the counter enable. Slave: counter starts on ITR1 (= TIM2 TRGO).
        dp.TIM2.cr2().modify(|_, w| w.mms().enable());
        dp.TIM3
            .smcr()
            .modify(|_, w| w.ts().itr1().sms().trigger_mode());
    }

    fn force_outputs_low(dp: &pac::Peripherals) {
        dp.TIM2
            .ccmr1_output()
            .modify(|_, w| w.oc1m().force_inactive().oc1pe().enabled());
        dp.TIM3
            .ccmr1_output()
            .modify(|_, w| w.oc1m().force_inactive().oc1pe().enabled());
    }

    /// Programs both timers from `plan`, parks each counter on its last count (output low in
    /// PWM mode 1), then sets TIM2's counter enable, which starts TIM3 through ITR1. The first
    /// tick of both counters wraps to 0: both first rising edges, together.
    fn start_timers(dp: &pac::Peripherals, plan: &TimerPlan, first_width: u16) {
        let (tim2, tim3) = (&dp.TIM2, &dp.TIM3);
        tim2.cr1().modify(|_, w| w.cen().clear_bit());
        tim3.cr1().modify(|_, w| w.cen().clear_bit());
        force_outputs_low(dp);

        tim2.psc().write(|w| w.psc().set(plan.prescaler()));
        tim2.arr().write(|w| w.arr().set(plan.depth_reload()));
        tim2.ccr1().write(|w| w.ccr().set(plan.depth_width_ticks()));
        tim3.psc().write(|w| w.psc().set(plan.prescaler()));
        tim3.arr().write(|w| w.arr().set(plan.event_reload()));
        tim3.ccr1().write(|w| w.ccr().set(first_width));
        // Preloaded reload; only real overflows raise the update interrupt.
        tim2.cr1().modify(|_, w| w.arpe().set_bit().urs().set_bit());
        tim3.cr1().modify(|_, w| w.arpe().set_bit().urs().set_bit());
        // Update generation loads prescaler, reload and compare and clears the prescaler count.
        tim2.egr().write(|w| w.ug().set_bit());
        tim3.egr().write(|w| w.ug().set_bit());
        tim2.cnt().write(|w| w.cnt().set(plan.depth_reload()));
        tim3.cnt().write(|w| w.cnt().set(plan.event_reload()));
        tim2.sr().write(|w| w.uif().clear_bit());
        tim3.sr().write(|w| w.uif().clear_bit());
        NVIC::unpend(Interrupt::TIM3);

        tim2.ccmr1_output().modify(|_, w| w.oc1m().pwm_mode1());
        tim3.ccmr1_output().modify(|_, w| w.oc1m().pwm_mode1());
        tim3.dier().modify(|_, w| w.uie().set_bit());
        dp.GPIOA.bsrr().write(|w| w.bs5().set_bit());
        tim2.cr1().modify(|_, w| w.cen().set_bit());
    }

    /// Drives both outputs low and stops both counters.
    fn stop_timers(dp: &pac::Peripherals) {
        force_outputs_low(dp);
        dp.TIM2.cr1().modify(|_, w| w.cen().clear_bit());
        dp.TIM3.cr1().modify(|_, w| w.cen().clear_bit());
        dp.TIM3.dier().modify(|_, w| w.uie().clear_bit());
        dp.TIM3.sr().write(|w| w.uif().clear_bit());
        NVIC::unpend(Interrupt::TIM3);
        dp.GPIOA.bsrr().write(|w| w.br5().set_bit());
    }

    /// Waits (bounded) until both outputs are low and the next rising edge is far off: the
    /// depth counter past its pulse, and the event counter past the widest event pulse but in
    /// the first half of what remains of its period.
    fn wait_outputs_low(dp: &pac::Peripherals, plan: &TimerPlan) {
        let coded = u32::from(plan.event_coded_width_ticks());
        let window_end = coded + (plan.event_period_ticks() - coded) / 2;
        let quiet = || {
            let t2 = dp.TIM2.cnt().read().cnt().bits();
            let t3 = u32::from(dp.TIM3.cnt().read().cnt().bits());
            t2 >= plan.depth_width_ticks() && (coded..window_end).contains(&t3)
        };
        if dp.TIM2.cr1().read().cen().bit_is_set() && !spin_until(quiet) {
            defmt::warn!("stop: no quiet window found in time, forcing outputs low");
        }
    }

    /// Polls `ready` at most `SPIN_LIMIT` times; true when it became true.
    fn spin_until(mut ready: impl FnMut() -> bool) -> bool {
        (0..SPIN_LIMIT).any(|_| ready())
    }

    /// Sends bytes, waiting (bounded) for the transmit register before each.
    fn write_uart(dp: &pac::Peripherals, bytes: &[u8]) {
        let usart = &dp.USART2;
        for &b in bytes {
            if !spin_until(|| usart.sr().read().txe().bit_is_set()) {
                return;
            }
            usart.dr().write(|w| w.dr().set(u16::from(b)));
        }
    }

    /// TIM3 update: an event pulse has just begun. Count it and preload the next width.
    #[interrupt]
    fn TIM3() {
        // SAFETY: this handler owns TIM3's status and compare registers while running; the
        // command loop touches them only with this interrupt masked (critical section).
        let tim3 = unsafe { &*pac::TIM3::ptr() };
        if tim3.sr().read().uif().bit_is_clear() {
            return;
        }
        tim3.sr().write(|w| w.uif().clear_bit());
        critical_section::with(|cs| {
            if let Some(width) = TRAIN
                .borrow_ref_mut(cs)
                .as_mut()
                .and_then(PulseTrain::on_event_pulse)
            {
                tim3.ccr1().write(|w| w.ccr().set(width));
            }
        });
    }

    /// USART2: move a received byte into the command buffer; count what is lost.
    #[interrupt]
    fn USART2() {
        // SAFETY: this handler only reads USART2's status and data registers.
        let usart = unsafe { &*pac::USART2::ptr() };
        let sr = usart.sr().read();
        if sr.rxne().bit_is_set() || sr.ore().bit_is_set() {
            // Reading DR after SR clears RXNE and the overrun flag.
            let byte = usart.dr().read().dr().bits() as u8;
            if sr.ore().bit_is_set() {
                RX_LOST.fetch_add(1, Ordering::Relaxed);
            }
            let full = critical_section::with(|cs| RX.borrow_ref_mut(cs).push_back(byte).is_err());
            if full {
                RX_LOST.fetch_add(1, Ordering::Relaxed);
            }
        }
    }
}
