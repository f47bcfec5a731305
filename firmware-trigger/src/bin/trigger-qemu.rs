//! QEMU variant of the trigger firmware for the `mps2-an386` machine (Cortex-M4).
//!
//! The machine has no STM32 timers, so this variant replays the board's schedule (the same
//! `TimerPlan` for 84 MHz: 6 MHz ticks, periods 200 000 / 50 000 ticks) from SysTick: every
//! SysTick interrupt is one group of simultaneous edges. mps2's SysTick counts the 25 MHz
//! processor clock, at which 30 Hz is not a whole number of cycles (the plan core refuses it,
//! and this firmware prints that refusal); edge times are therefore mapped from 6 MHz ticks to
//! the nearest 25 MHz cycle on the absolute time axis, so each edge is within half a cycle of
//! ideal and nothing accumulates.
//!
//! SysTick is reprogrammed one interval ahead: its reload value is latched when the counter
//! wraps, so the interrupt for group `k` writes the interval between groups `k + 1` and `k + 2`,
//! and interrupt latency never enters the intervals.
//!
//! Each interrupt reads CMSDK APB timer 0 (a free-running 25 MHz down-counter at 0x4000_0000)
//! as an independent measurement of when it ran, and the main loop reports every edge over
//! semihosting as `E <measured_cycles> <depth|event> <rise|fall> <index> <ticks>`. It runs
//! 36 depth periods (1.2 s of virtual time), stops the pulse train, prints a summary line
//! `S ...` and exits through semihosting. Run it with deterministic virtual time:
//! `qemu-system-arm -M mps2-an386 -icount shift=3,align=off,sleep=off -semihosting-config
//! enable=on,target=native -nographic -kernel trigger-qemu`.
#![cfg_attr(target_os = "none", no_std)]
#![cfg_attr(target_os = "none", no_main)]

/// Host builds (e.g. `--all-features` on the workspace) get a stub that says where this runs.
#[cfg(not(target_os = "none"))]
fn main() {
    eprintln!(
        "trigger-qemu runs under qemu-system-arm -M mps2-an386; build it with --target thumbv7em-none-eabihf --features qemu"
    );
    std::process::exit(2);
}

#[cfg(target_os = "none")]
mod firmware {
    use core::cell::RefCell;
    use core::panic::PanicInfo;
    use core::ptr;

    use cortex_m::asm;
    use cortex_m::peripheral::SYST;
    use cortex_m::peripheral::syst::SystClkSource;
    use cortex_m_rt::{entry, exception};
    use cortex_m_semihosting::{debug, hprintln};
    use critical_section::Mutex;
    use firmware_trigger::{
        BOARD_TIMER_CLOCK_HZ, DEFAULT_DEPTH_HZ, Edge, EdgeSchedule, Line, PulseTrain, PulseWidths,
        TimerPlan, rescale,
    };
    use heapless::{Deque, Vec};

    /// mps2 SYSCLK, Hz: the processor clock SysTick counts, and the APB timers' clock.
    const CPU_HZ: u32 = 25_000_000;
    /// Cycles from enabling SysTick to the first edges (room to program the second interval).
    const LEAD_CYCLES: u64 = 25_000;
    /// Depth periods to run: 36 at 30 Hz is 1.2 s of virtual time.
    const RUN_DEPTH_PULSES: u64 = 36;
    /// CMSDK APB timer 0 registers: control, current value, reload.
    const TIMER0_CTRL: *mut u32 = 0x4000_0000 as *mut u32;
    const TIMER0_VALUE: *const u32 = 0x4000_0004 as *const u32;
    const TIMER0_RELOAD: *mut u32 = 0x4000_0008 as *mut u32;
    /// SysTick's reload register is 24 bits wide.
    const SYST_MAX_RELOAD: u64 = 0x00ff_ffff;

    /// Edges that share one tick, and the SysTick cycle they are due at.
    struct Group {
        at_cycles: u64,
        edges: Vec<Edge, 4>,
    }

    /// One serviced interrupt: when timer 0 says it ran, and the edges it emitted.
    struct Record {
        measured: u32,
        edges: Vec<Edge, 4>,
    }

    /// Everything the SysTick handler owns.
    struct Driver {
        syst: SYST,
        schedule: EdgeSchedule,
        train: PulseTrain,
        tick_hz: u32,
        end_ticks: u64,
        /// Groups whose intervals are already programmed: the front one is due next.
        due: Deque<Group, 2>,
        /// Width the board would have preloaded for the next event pulse.
        preload: u16,
        width_mismatches: u32,
        lost_records: u32,
        done: bool,
    }

    impl Driver {
        /// The next group of simultaneous edges before the end of the run.
        fn next_group(&mut self) -> Option<Group> {
            let t = self.schedule.peek_time();
            if t >= self.end_ticks {
                return None;
            }
            let mut edges = Vec::new();
            while self.schedule.peek_time() == t {
                let edge = self.schedule.next()?;
                if edges.push(edge).is_err() {
                    break;
                }
            }
            Some(Group {
                at_cycles: LEAD_CYCLES + rescale(t, self.tick_hz, CPU_HZ),
                edges,
            })
        }

        /// Emits the due group: drives the pulse train for its event rising edges, exactly as
        /// the board's update interrupt does, and checks the widths it hands out.
        fn emit(&mut self, group: &Group) {
            for e in group
                .edges
                .iter()
                .filter(|e| e.rising && e.line == Line::Event)
            {
                let expected_now = self.train.plan().event_width_for(e.index);
                if self.preload != expected_now || self.train.counts().event != e.index {
                    self.width_mismatches += 1;
                }
                match self.train.on_event_pulse() {
                    Some(next) => self.preload = next,
                    None => self.width_mismatches += 1,
                }
            }
        }
    }

    static DRIVER: Mutex<RefCell<Option<Driver>>> = Mutex::new(RefCell::new(None));
    static RECORDS: Mutex<RefCell<Deque<Record, 32>>> = Mutex::new(RefCell::new(Deque::new()));

    fn timer0_elapsed() -> u32 {
        // SAFETY: CMSDK APB timer 0 is a memory-mapped device on mps2; reading VALUE has no
        // side effects.
        let value = unsafe { ptr::read_volatile(TIMER0_VALUE) };
        u32::MAX - value
    }

    fn fail(msg: &str) -> ! {
        hprintln!("X {}", msg);
        debug::exit(debug::EXIT_FAILURE);
        loop {
            asm::wfi();
        }
    }

    #[entry]
    fn main() -> ! {
        let Some(cp) = cortex_m::Peripherals::take() else {
            fail("core peripherals already taken");
        };
        let plan = match TimerPlan::new(
            BOARD_TIMER_CLOCK_HZ,
            DEFAULT_DEPTH_HZ,
            PulseWidths::default(),
        ) {
            Ok(plan) => plan,
            Err(e) => {
                hprintln!("X no plan: {}", e);
                fail("no plan");
            }
        };
        if let Err(e) = TimerPlan::new(CPU_HZ, DEFAULT_DEPTH_HZ, PulseWidths::default()) {
            hprintln!("N direct plan at {} Hz refused: {}", CPU_HZ, e);
        }
        hprintln!(
            "P tick_hz={} cpu_hz={} psc={} depth_arr={} event_arr={} widths={}/{}/{}",
            plan.tick_hz(),
            CPU_HZ,
            plan.prescaler(),
            plan.depth_reload(),
            plan.event_reload(),
            plan.depth_width_ticks(),
            plan.event_width_ticks(),
            plan.event_coded_width_ticks()
        );

        // Free-running measurement clock.
        // SAFETY: CMSDK APB timer 0 registers on mps2; writing reload then enable starts it.
        unsafe {
            ptr::write_volatile(TIMER0_RELOAD, u32::MAX);
            ptr::write_volatile(TIMER0_CTRL, 1);
        }

        let mut train = PulseTrain::new(plan);
        let preload = match train.start() {
            Ok(w) => w,
            Err(_) => fail("train refused to start"),
        };
        let mut driver = Driver {
            syst: cp.SYST,
            schedule: EdgeSchedule::new(&plan),
            train,
            tick_hz: plan.tick_hz(),
            end_ticks: RUN_DEPTH_PULSES * u64::from(plan.depth_period_ticks()),
            due: Deque::new(),
            preload,
            width_mismatches: 0,
            lost_records: 0,
            done: false,
        };
        let (Some(first), Some(second)) = (driver.next_group(), driver.next_group()) else {
            fail("empty schedule");
        };
        let interval = second.at_cycles - first.at_cycles;
        if first.at_cycles > SYST_MAX_RELOAD + 1 || interval > SYST_MAX_RELOAD + 1 {
            fail("interval exceeds SysTick's 24 bits");
        }
        let syst = &mut driver.syst;
        syst.set_clock_source(SystClkSource::Core);
        syst.set_reload((first.at_cycles - 1) as u32);
        syst.clear_current();
        syst.enable_interrupt();
        let _ = driver.due.push_back(first);
        let _ = driver.due.push_back(second);
        critical_section::with(|cs| {
            let mut slot = DRIVER.borrow_ref_mut(cs);
            let driver = slot.insert(driver);
            driver.syst.enable_counter();
            // The counter latches the first reload on its first cycle; only then may the
            // second interval be written (it takes effect at the first wrap).
            let mut spins = 0u32;
            while SYST::get_current() == 0 && spins < 1_000 {
                spins += 1;
            }
            driver.syst.set_reload((interval - 1) as u32);
        });

        loop {
            let (record, finished) = critical_section::with(|cs| {
                let record = RECORDS.borrow_ref_mut(cs).pop_front();
                let finished = DRIVER.borrow_ref(cs).as_ref().is_none_or(|d| d.done);
                if record.is_none() && !finished {
                    asm::wfi();
                }
                (record, finished)
            });
            match record {
                Some(r) => {
                    for e in &r.edges {
                        let line = match e.line {
                            Line::Depth => "depth",
                            Line::Event => "event",
                        };
                        let dir = if e.rising { "rise" } else { "fall" };
                        hprintln!(
                            "E {} {} {} {} {}",
                            r.measured,
                            line,
                            dir,
                            e.index,
                            e.t_ticks
                        );
                    }
                }
                None if finished => break,
                None => {}
            }
        }
        let summary = critical_section::with(|cs| {
            DRIVER.borrow_ref_mut(cs).as_mut().map(|d| {
                let stopped = d.train.stop().is_ok();
                let counts = d.train.counts();
                (stopped, counts, d.width_mismatches, d.lost_records)
            })
        });
        match summary {
            Some((stopped, counts, mismatches, lost)) => {
                hprintln!(
                    "S event_pulses={} depth_pulses={} stopped={} width_mismatches={} lost_records={}",
                    counts.event,
                    counts.depth,
                    stopped,
                    mismatches,
                    lost
                );
                debug::exit(debug::EXIT_SUCCESS);
            }
            None => fail("driver missing"),
        }
        loop {
            asm::wfi();
        }
    }

    #[exception]
    fn SysTick() {
        let measured = timer0_elapsed();
        critical_section::with(|cs| {
            let mut slot = DRIVER.borrow_ref_mut(cs);
            let Some(d) = slot.as_mut() else { return };
            let Some(group) = d.due.pop_front() else {
                d.syst.disable_counter();
                d.done = true;
                return;
            };
            d.emit(&group);
            // The counter has just reloaded with the interval to the now-front group; program
            // the interval after it.
            match (d.due.front().map(|g| g.at_cycles), d.next_group()) {
                (Some(next_at), Some(after)) => {
                    let interval = (after.at_cycles - next_at).clamp(1, SYST_MAX_RELOAD + 1);
                    d.syst.set_reload((interval - 1) as u32);
                    let _ = d.due.push_back(after);
                }
                (Some(_), None) => {}
                (None, _) => {
                    d.syst.disable_counter();
                    d.done = true;
                }
            }
            let record = Record {
                measured,
                edges: group.edges,
            };
            if RECORDS.borrow_ref_mut(cs).push_back(record).is_err() {
                d.lost_records += 1;
            }
        });
    }

    #[panic_handler]
    fn panic(info: &PanicInfo) -> ! {
        hprintln!("X panic: {}", info);
        debug::exit(debug::EXIT_FAILURE);
        loop {
            asm::wfi();
        }
    }
}
