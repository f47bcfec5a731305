//! Host tests of the UART command interface: grammar, replies, refusal of garbage, bounded
//! buffers.

#![allow(clippy::unwrap_used, clippy::expect_used)]

use firmware_trigger::command::{
    Action, Command, CommandError, LINE_CAPACITY, LineBuffer, REPLY_CAPACITY, Reply, execute,
    parse, refuse, refuse_no_plan,
};
use firmware_trigger::{BOARD_TIMER_CLOCK_HZ, PulseTrain, PulseWidths, TimerPlan};

fn train() -> PulseTrain {
    PulseTrain::new(TimerPlan::new(BOARD_TIMER_CLOCK_HZ, 30, PulseWidths::default()).unwrap())
}

/// Feeds bytes and returns every reply the firmware would send, as the board's main loop does.
fn session(train: &mut PulseTrain, input: &[u8]) -> Vec<String> {
    let mut lines = LineBuffer::new();
    let mut reply = Reply::new();
    let mut out = Vec::new();
    for &b in input {
        if let Some(outcome) = lines.push(b) {
            match outcome {
                Ok(cmd) => {
                    execute(cmd, train, &mut reply);
                }
                Err(e) => refuse(&e, &mut reply),
            }
            assert!(
                reply.ends_with("\r\n"),
                "every reply is one whole line: {reply:?}"
            );
            out.push(reply.trim_end().to_owned());
        }
    }
    out
}

#[test]
fn parses_the_four_commands() {
    assert_eq!(parse("start"), Ok(Command::Start));
    assert_eq!(parse("  STOP "), Ok(Command::Stop));
    assert_eq!(parse("status"), Ok(Command::Status));
    assert_eq!(parse("rate"), Ok(Command::Rate(None)));
    assert_eq!(parse("rate\t15"), Ok(Command::Rate(Some(15))));
    assert_eq!(parse("start now"), Err(CommandError::UnexpectedArgument));
    assert_eq!(parse("rate fast"), Err(CommandError::BadRate));
    assert_eq!(parse("rate -3"), Err(CommandError::BadRate));
    assert_eq!(parse("rate 99999999999"), Err(CommandError::BadRate));
    assert_eq!(parse("rate 30 60"), Err(CommandError::BadRate));
    assert_eq!(parse("st\u{e9}p"), Err(CommandError::NotText));
    assert!(matches!(parse("launch"), Err(CommandError::Unknown(w)) if w == "launch"));
}

#[test]
fn start_status_stop_round_trip() {
    let mut t = train();
    let replies = session(&mut t, b"status\r\nstart\r\nstart\nstatus\n");
    assert_eq!(
        replies[0],
        "ok stopped depth_hz=30 event_hz=120 event_pulses=0 depth_pulses=0 runs=0"
    );
    assert_eq!(replies[1], "ok started depth_hz=30 event_hz=120");
    assert_eq!(replies[2], "err already running");
    assert!(replies[3].starts_with("ok running"), "{}", replies[3]);
    // Five update interrupts, then stop.
    for _ in 0..5 {
        t.on_event_pulse();
    }
    let replies = session(&mut t, b"stop\rstop\r");
    assert_eq!(replies[0], "ok stopped event_pulses=5 depth_pulses=2");
    assert_eq!(replies[1], "err not running");
}

#[test]
fn execute_tells_the_board_what_to_do_with_the_timers() {
    let mut t = train();
    let mut reply = Reply::new();
    assert_eq!(
        execute(Command::Start, &mut t, &mut reply),
        Action::Start { first_width: 1200 }
    );
    assert_eq!(execute(Command::Start, &mut t, &mut reply), Action::None);
    assert_eq!(execute(Command::Status, &mut t, &mut reply), Action::None);
    assert_eq!(execute(Command::Stop, &mut t, &mut reply), Action::Stop);
    assert_eq!(execute(Command::Stop, &mut t, &mut reply), Action::None);
}

#[test]
fn rate_reports_and_replans_only_while_stopped() {
    let mut t = train();
    let replies = session(
        &mut t,
        b"rate\nrate 15\nrate 11\nrate 0\nstart\nrate 30\nstop\nrate 30\n",
    );
    assert_eq!(
        replies[0],
        "ok depth_hz=30 event_hz=120 clock_hz=84000000 psc=13 depth_arr=199999 event_arr=49999 widths_ticks=6000/600/1200"
    );
    assert!(
        replies[1].starts_with("ok depth_hz=15 event_hz=60 "),
        "{}",
        replies[1]
    );
    assert!(
        replies[2].starts_with("err ") && replies[2].contains("11 Hz"),
        "{}",
        replies[2]
    );
    assert!(replies[3].starts_with("err "), "{}", replies[3]);
    assert_eq!(replies[4], "ok started depth_hz=15 event_hz=60");
    assert_eq!(replies[5], "err running: stop first");
    assert!(replies[6].starts_with("ok stopped"));
    assert!(replies[7].starts_with("ok depth_hz=30 "));
    assert_eq!(t.plan().depth_hz(), 30);
}

#[test]
fn garbage_gets_an_error_and_the_next_line_still_works() {
    let mut t = train();
    let mut input = Vec::new();
    input.extend_from_slice(b"hello\n");
    input.extend_from_slice(&[0xff, 0x00, 0x1b, b'[', b'A', b'\n']);
    input.extend_from_slice(&[b'x'; 200]);
    input.extend_from_slice(b"\nstatus\n\n\r\n  \nsta\x08\x08tatus\n");
    let replies = session(&mut t, &input);
    assert_eq!(replies.len(), 5, "{replies:?}");
    assert!(replies[0].starts_with("err unknown command 'hello'"));
    assert_eq!(replies[1], "err line is not printable ASCII");
    assert_eq!(
        replies[2],
        format!("err line too long (max {LINE_CAPACITY} bytes)")
    );
    assert!(replies[3].starts_with("ok stopped"));
    assert!(
        replies[4].starts_with("ok stopped"),
        "backspace edits: {}",
        replies[4]
    );
}

#[test]
fn random_bytes_never_panic_and_every_line_gets_one_reply() {
    // Deterministic xorshift: bytes from the whole range, with line ends sprinkled in.
    let mut state = 0x2545_f491_4f6c_dd1du64;
    let mut input = Vec::with_capacity(200_000);
    for _ in 0..200_000 {
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        let b = (state >> 24) as u8;
        input.push(if b.is_multiple_of(17) { b'\n' } else { b });
    }
    let mut t = train();
    let replies = session(&mut t, &input);
    // The lines that deserve a reply, from the protocol's rules: a line end closes a line; backspace and DEL
    // erase the last byte; a line that ran past the buffer gets one `too long` reply; a blank line gets none.
    let mut expected = 0;
    let mut line: std::vec::Vec<u8> = std::vec::Vec::new();
    let mut overflowed = false;
    for &b in &input {
        match b {
            b'\r' | b'\n' => {
                if overflowed || line.iter().any(|c| !c.is_ascii_whitespace()) {
                    expected += 1;
                }
                line.clear();
                overflowed = false;
            }
            0x08 | 0x7f => {
                line.pop();
            }
            _ if overflowed => {}
            _ if line.len() == LINE_CAPACITY => {
                overflowed = true;
                line.clear();
            }
            _ => line.push(b),
        }
    }
    assert!(
        expected > 1000,
        "the input exercises many lines: {expected}"
    );
    assert_eq!(replies.len(), expected);
    for r in &replies {
        assert!(r.starts_with("ok ") || r.starts_with("err "), "{r:?}");
        assert!(r.len() + 2 <= REPLY_CAPACITY);
    }
}

#[test]
fn longest_replies_fit_without_truncation() {
    let mut reply = Reply::new();
    // Largest numbers in a status line.
    let mut t = train();
    t.start().unwrap();
    execute(Command::Status, &mut t, &mut reply);
    assert!(reply.ends_with("runs=1\r\n"));
    // Longest refusal: the 4:1 message with ten-digit numbers.
    let err = TimerPlan::new(u32::MAX - 1, u32::MAX / 4, PulseWidths::default()).unwrap_err();
    refuse_no_plan(&err, &mut reply);
    assert!(reply.ends_with("\r\n") && reply.len() <= REPLY_CAPACITY);
    assert!(reply.contains("cannot"), "whole message kept: {reply}");
    let word = "x".repeat(LINE_CAPACITY);
    let mut lines = LineBuffer::new();
    let mut outcome = None;
    for b in word.bytes().chain(*b"\n") {
        outcome = lines.push(b).or(outcome);
    }
    refuse(&outcome.unwrap().unwrap_err(), &mut reply);
    assert!(reply.contains("rate [HZ])"), "whole message kept: {reply}");
}
