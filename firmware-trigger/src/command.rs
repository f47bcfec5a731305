//! The UART command interface: a bounded line assembler, the command grammar and the replies.
//!
//! Grammar (one command per line, `\r`, `\n` or both end a line, ASCII case ignored):
//! `start`, `stop`, `status`, `rate` (report the plan) and `rate HZ` (new depth rate, while
//! stopped). Every line gets exactly one reply line starting `ok` or `err`. Garbage (unknown
//! words, bad numbers, non-text bytes, over-long lines) gets an `err` reply; nothing blocks and
//! all buffers are fixed-size (`heapless`).

use core::fmt::{self, Write};

use heapless::{String, Vec};

use crate::plan::{PlanError, TimerPlan};
use crate::train::PulseTrain;

/// Longest accepted command line in bytes, excluding the line end.
pub const LINE_CAPACITY: usize = 32;

/// Capacity of one reply line in bytes, including the trailing `\r\n`.
pub const REPLY_CAPACITY: usize = 192;

/// One reply line.
pub type Reply = String<REPLY_CAPACITY>;

/// A parsed command.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Command {
    /// Start both pulse trains together.
    Start,
    /// Stop both pulse trains (after the pulses in progress have ended).
    Stop,
    /// Report run state and pulse counts.
    Status,
    /// `rate`: report the plan; `rate HZ`: plan a new depth rate (event rate is 4 x).
    Rate(Option<u32>),
}

/// Why a line is not a command.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum CommandError {
    /// The line exceeded [`LINE_CAPACITY`] bytes (the rest of it was discarded).
    TooLong,
    /// The line held bytes other than printable ASCII and tabs.
    NotText,
    /// The first word is not a command (the word is echoed back, it is printable ASCII).
    Unknown(Word),
    /// A command that takes no argument got one.
    UnexpectedArgument,
    /// `rate` got something other than one decimal number of Hz.
    BadRate,
}

/// A short printable-ASCII word copied out of a command line, for error replies.
pub type Word = String<LINE_CAPACITY>;

impl fmt::Display for CommandError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            CommandError::TooLong => write!(f, "line too long (max {LINE_CAPACITY} bytes)"),
            CommandError::NotText => f.write_str("line is not printable ASCII"),
            CommandError::Unknown(word) => write!(
                f,
                "unknown command '{word}' (commands: start, stop, status, rate [HZ])"
            ),
            CommandError::UnexpectedArgument => f.write_str("this command takes no argument"),
            CommandError::BadRate => f.write_str("usage: rate [HZ] with HZ a whole number"),
        }
    }
}

/// Parses one line (without its line end) into a command.
pub fn parse(line: &str) -> Result<Command, CommandError> {
    if !line
        .bytes()
        .all(|b| b == b'\t' || (0x20..0x7f).contains(&b))
    {
        return Err(CommandError::NotText);
    }
    let mut words = line.split_ascii_whitespace();
    let Some(first) = words.next() else {
        return Err(CommandError::Unknown(Word::new()));
    };
    let arg = words.next();
    let more = words.next().is_some();
    let no_arg = |cmd| {
        if arg.is_some() {
            Err(CommandError::UnexpectedArgument)
        } else {
            Ok(cmd)
        }
    };
    if first.eq_ignore_ascii_case("start") {
        no_arg(Command::Start)
    } else if first.eq_ignore_ascii_case("stop") {
        no_arg(Command::Stop)
    } else if first.eq_ignore_ascii_case("status") {
        no_arg(Command::Status)
    } else if first.eq_ignore_ascii_case("rate") {
        match (arg, more) {
            (None, _) => Ok(Command::Rate(None)),
            (Some(hz), false) if hz.bytes().all(|b| b.is_ascii_digit()) => hz
                .parse::<u32>()
                .map(|hz| Command::Rate(Some(hz)))
                .map_err(|_| CommandError::BadRate),
            _ => Err(CommandError::BadRate),
        }
    } else {
        let mut word = Word::new();
        for c in first.chars() {
            if word.push(c).is_err() {
                break;
            }
        }
        Err(CommandError::Unknown(word))
    }
}

/// Assembles bytes from the UART into lines and parses them. Never allocates, never blocks:
/// an over-long line is discarded up to its end and reported once as [`CommandError::TooLong`].
#[derive(Clone, Debug, Default)]
pub struct LineBuffer {
    buf: Vec<u8, LINE_CAPACITY>,
    overflowed: bool,
}

impl LineBuffer {
    /// An empty buffer.
    pub fn new() -> Self {
        Self::default()
    }

    /// Feeds one received byte. Returns the outcome when the byte ends a non-empty line;
    /// blank lines (e.g. the `\n` of a `\r\n`) give nothing. Backspace and DEL erase.
    pub fn push(&mut self, byte: u8) -> Option<Result<Command, CommandError>> {
        match byte {
            b'\r' | b'\n' => {
                let overflowed = core::mem::replace(&mut self.overflowed, false);
                let outcome = if overflowed {
                    Some(Err(CommandError::TooLong))
                } else if self.buf.iter().all(|b| b.is_ascii_whitespace()) {
                    None
                } else {
                    Some(match core::str::from_utf8(&self.buf) {
                        Ok(line) => parse(line),
                        Err(_) => Err(CommandError::NotText),
                    })
                };
                self.buf.clear();
                outcome
            }
            0x08 | 0x7f => {
                self.buf.pop();
                None
            }
            _ => {
                if !self.overflowed && self.buf.push(byte).is_err() {
                    self.overflowed = true;
                    self.buf.clear();
                }
                None
            }
        }
    }
}

/// What the caller must do to the hardware after [`execute`] changed the run state.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Action {
    /// Nothing to do.
    None,
    /// Program both timers from the train's plan, preload `first_width` ticks for event
    /// pulse 0, then start the master (which starts the slave through the internal trigger).
    Start {
        /// Width in ticks of event pulse 0.
        first_width: u16,
    },
    /// Stop both timers with their outputs low.
    Stop,
}

/// Applies a command to the generator's run state and writes the reply line (ending `\r\n`).
/// The caller performs the returned hardware [`Action`].
pub fn execute(cmd: Command, train: &mut PulseTrain, reply: &mut Reply) -> Action {
    reply.clear();
    let mut action = Action::None;
    // A reply that does not fit is cut short, never an error: every reply is sized to fit.
    let _ = match cmd {
        Command::Start => match train.start() {
            Ok(first_width) => {
                action = Action::Start { first_width };
                write!(reply, "ok started ").and_then(|()| write_rates(reply, train.plan()))
            }
            Err(e) => write!(reply, "err {e}"),
        },
        Command::Stop => match train.stop() {
            Ok(counts) => {
                action = Action::Stop;
                write!(
                    reply,
                    "ok stopped event_pulses={} depth_pulses={}",
                    counts.event, counts.depth
                )
            }
            Err(e) => write!(reply, "err {e}"),
        },
        Command::Status => {
            let counts = train.counts();
            let state = if train.is_running() {
                "running"
            } else {
                "stopped"
            };
            write!(reply, "ok {state} ")
                .and_then(|()| write_rates(reply, train.plan()))
                .and_then(|()| {
                    write!(
                        reply,
                        " event_pulses={} depth_pulses={} runs={}",
                        counts.event,
                        counts.depth,
                        train.runs()
                    )
                })
        }
        Command::Rate(None) => write_plan(reply, train.plan()),
        Command::Rate(Some(hz)) => {
            let plan = *train.plan();
            match TimerPlan::new(plan.clock_hz(), hz, plan.widths()) {
                Ok(new_plan) => match train.set_plan(new_plan) {
                    Ok(()) => write_plan(reply, train.plan()),
                    Err(e) => write!(reply, "err {e}"),
                },
                Err(e) => write!(reply, "err {e}"),
            }
        }
    };
    end_line(reply);
    action
}

/// Writes the reply for a line that is not a command.
pub fn refuse(err: &CommandError, reply: &mut Reply) {
    reply.clear();
    let _ = write!(reply, "err {err}");
    end_line(reply);
}

/// Writes the reply to any command when no exact plan exists (e.g. the crystal did not start
/// and the timers run from an inexact clock): the generator refuses to run.
pub fn refuse_no_plan(err: &PlanError, reply: &mut Reply) {
    reply.clear();
    let _ = write!(reply, "err no exact timer plan: {err}");
    end_line(reply);
}

fn write_rates(reply: &mut Reply, plan: &TimerPlan) -> fmt::Result {
    write!(
        reply,
        "depth_hz={} event_hz={}",
        plan.depth_hz(),
        plan.event_hz()
    )
}

fn write_plan(reply: &mut Reply, plan: &TimerPlan) -> fmt::Result {
    write!(reply, "ok ")?;
    write_rates(reply, plan)?;
    write!(
        reply,
        " clock_hz={} psc={} depth_arr={} event_arr={} widths_ticks={}/{}/{}",
        plan.clock_hz(),
        plan.prescaler(),
        plan.depth_reload(),
        plan.event_reload(),
        plan.depth_width_ticks(),
        plan.event_width_ticks(),
        plan.event_coded_width_ticks()
    )
}

/// Terminates a reply with `\r\n`, cutting its text if needed so the line end always fits.
fn end_line(reply: &mut Reply) {
    while reply.len() > REPLY_CAPACITY - 2 {
        reply.pop();
    }
    let _ = reply.push_str("\r\n");
}
