//! `hil-sim`: the hardware-in-the-loop simulator's command-line tool.

use anyhow::Context;
use clap::builder::{PossibleValuesParser, TypedValueParser};
use clap::{CommandFactory, Parser, Subcommand};
use drivers::event::Geometry;
use hil_sim::generate::{Companion, GenerateConfig, ObjectSource, generate};
use hil_sim::motion::{MotionProfile, SpeedLevel};
use hil_sim::objects::ObjectKind;
use hil_sim::pattern::{RotatingBar, write_rotating_bar};
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use std::fs::File;
use std::io::BufWriter;
use std::path::PathBuf;
use std::process::ExitCode;

/// Synthetic event + depth + ground-truth recordings for EventTrack6D, without hardware.
#[derive(Debug, Parser)]
#[command(name = "hil-sim", version, propagate_version = true)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Debug, Subcommand)]
enum Command {
    /// Generate one recording without hardware.
    ///
    /// A textured object from the procedural library (or a novel procedural shape, or your OBJ, in metres) moves
    /// after one of the paper's motion profiles in front of a static EVK4-like event camera (1280x720, fx 1000 px)
    /// and a D435i-like depth camera (848x480, 30 Hz, 6 cm to the side), with a textured wall and table and a
    /// hand-like occluder gripping the object. The recording holds ESIM events with the rig's trigger train
    /// (events.raw), RealSense-like depth frames, the cameras, ground truth at 1 kHz plus every tick, and the
    /// object meshes. The same seed gives byte-identical recordings. A progress bar shows the simulated time. The
    /// format: docs/recording-format.md; the simulation: docs/simulator.md.
    Generate {
        /// Library object name (cracker_box, pudding_box, can, bottle, mug, bowl, banana, hammer, spatula,
        /// drill, marker, wine_glass); a procedurally generated object of a shape family the library lacks,
        /// `novel:SEED` (the family by SEED mod 6: superquadric, star_prism, torus, bracket, twisted_prism,
        /// holed_frustum) or by its name `novel_<family>_<seed>` (its shape and texture depend on these only, not on
        /// --seed); or a path to an `.obj` file.
        #[arg(long)]
        object: String,
        /// Motion profile: translation, rotation, shake, throw (ballistic flight with spin between two hands),
        /// hand-switch, depth (towards and away from the camera).
        #[arg(long, default_value = "shake", value_parser = motion_parser())]
        motion: MotionProfile,
        /// Speed level: slow (about 0.3 m/s, up to 2 rad/s), moderate (1 m/s, 6 rad/s), fast (2 m/s on average,
        /// up to 15 rad/s).
        #[arg(long, default_value = "moderate", value_parser = speed_parser())]
        speed: SpeedLevel,
        /// Length, seconds, in [0.01, 600].
        #[arg(long, value_name = "S", default_value_t = 3.0)]
        seconds: f64,
        /// Seed of everything random; the same seed gives the same recording, byte for byte.
        #[arg(long, value_name = "N", default_value_t = 1)]
        seed: u64,
        /// Output recording directory (created; files in it are overwritten).
        #[arg(long, value_name = "DIR")]
        out: PathBuf,
        /// Probability that a depth frame is dropped, in [0, 1].
        #[arg(long, value_name = "P", default_value_t = 0.0)]
        drop_depth: f64,
        /// Background noise events per pixel per second, in [0, 100].
        #[arg(long, value_name = "RATE", default_value_t = 0.05)]
        noise_hz: f64,
        /// Leave out the hand-like occluders.
        #[arg(long)]
        no_hands: bool,
        /// A further object in the scene, tracked too (repeatable): an object as for --object, its motion
        /// and speed (default: those of `--object`) and where its trajectory is centred relative to the first
        /// object's, metres in the camera frame (default: 15 cm nearer the camera per further object, so it
        /// passes in front of the others). Each has its own hand and its own seed; names must differ. E.g.
        /// `--with can:translation:slow:0.05,0,-0.15`.
        #[arg(long = "with", value_name = "NAME[:MOTION[:SPEED[:X,Y,Z]]]")]
        with: Vec<String>,
    },
    /// Generate a fixed, named suite of recordings, reusing those already generated with the same parameters.
    ///
    /// `dev`: every library object under three motion profiles, at slow, moderate and fast speed (36 sequences,
    /// 3 s each). `holdout`: the same shape with other seeds and each object under other motion-speed pairs, to
    /// check a change tuned on `dev`. `smoke`: two 1 s sequences. `multi`: 12 scenes of two objects that hide each
    /// other, 2-3 s each. `fast`: 36 sequences of 3 s at fast speed, the library objects twice on new seeds and
    /// pairings (groups dev-like and holdout-like) and 12 novel objects (group novel, named novel_*). `fast-check`:
    /// the shape of `fast` on seeds, pairings and novel shapes no other suite has, to check a result tuned on `fast`.
    /// Writes DIR/<sequence>/ and DIR/suite.json. Each sequence has its own seed, so the
    /// recordings do not depend on --jobs. Progress lines name each sequence as it finishes; after a failure no
    /// further sequence is started and the first error is reported. Suite contents and generation times:
    /// docs/simulator.md.
    Suite {
        /// Suite name: dev, holdout (dev's shape, other seeds and pairings), smoke, multi (two objects per scene),
        /// fast (fast motion only, library and novel objects) or fast-check (fast's shape on other seeds and shapes).
        #[arg(long, default_value = "dev", value_parser = PossibleValuesParser::new(hil_sim::suite::SUITES))]
        name: String,
        /// Output directory: one recording directory per sequence, and suite.json.
        #[arg(long, value_name = "DIR")]
        out: PathBuf,
        /// Sequences generated at once, 1 to 256 (default: one per available core); each renders on one thread and
        /// simulates the event sensor on another. The recordings do not depend on it; memory grows by about
        /// 160 MiB per job.
        #[arg(long, value_name = "N", value_parser = clap::value_parser!(u32).range(1..=256))]
        jobs: Option<u32>,
    },
    /// Write pictures of a recording at the given times.
    ///
    /// For each time T: events_<ms>.png, the events of the 5 ms before T (red ON, blue OFF, white background) with
    /// the ground-truth object contour in green, and depth_<ms>.png, the latest depth frame (near = bright, no
    /// measurement = purple). Prints the paths written.
    Preview {
        /// Recording directory.
        dir: PathBuf,
        /// Times, seconds from the start of the recording.
        #[arg(long, value_name = "T", num_args = 1.., required = true)]
        at: Vec<f64>,
        /// Output directory (default DIR/preview).
        #[arg(long, value_name = "OUT")]
        out: Option<PathBuf>,
    },
    /// Write a rotating-bar test pattern as an EVT 3.0 `.raw` stream with the rig's trigger train.
    ///
    /// 1280x720; each pixel the bar sweeps fires one ON and one OFF event per revolution, plus background noise.
    /// The trigger train is on channel 0: 120 Hz pulses of 100 us, every 4th one 200 us wide (a depth exposure),
    /// as the trigger MCU emits them.
    Pattern {
        /// Output `.raw` (or `.evt3`) file (overwritten; its folder is created).
        #[arg(long, value_name = "FILE")]
        out: PathBuf,
        /// Length, seconds, in (0, 3600].
        #[arg(long, value_name = "S", default_value_t = 2.0)]
        seconds: f64,
        /// Rotation rate, revolutions per second, in (0, 100].
        #[arg(long, value_name = "R", default_value_t = 1.0)]
        revolutions_per_s: f64,
        /// Noise events per pixel per second, in [0, 1000].
        #[arg(long, value_name = "RATE", default_value_t = 0.1)]
        noise_hz: f64,
        /// Seed of the noise.
        #[arg(long, value_name = "N", default_value_t = 1)]
        seed: u64,
    },
    UsbCamera(hil_sim::usb_camera::args::UsbCameraArgs),
    Ros2Play(hil_sim::ros2_play::args::Ros2PlayArgs),
    /// Print the command reference (docs/commands-hil-sim.md) as Markdown, from these commands' own help texts.
    #[command(hide = true)]
    Reference,
}

/// `--motion`: the profiles' names, so that `--help` and the reference list them.
fn motion_parser() -> impl TypedValueParser<Value = MotionProfile> {
    PossibleValuesParser::new(MotionProfile::ALL.map(MotionProfile::name))
        .try_map(|s| s.parse::<MotionProfile>())
}

/// `--speed`: the levels' names, so that `--help` and the reference list them.
fn speed_parser() -> impl TypedValueParser<Value = SpeedLevel> {
    PossibleValuesParser::new(SpeedLevel::ALL.map(SpeedLevel::name))
        .try_map(|s| s.parse::<SpeedLevel>())
}

/// What `hil-sim reference` (docs/commands-hil-sim.md) says besides the commands.
const REFERENCE_PAGE: cli_reference::Page<'static> = cli_reference::Page {
    defined_in: "hil-sim/src/main.rs",
    regenerate: "ET6D_WRITE_DOCS=1 cargo test -p hil-sim --test reference",
    see_also: "The tracker's commands are in [commands.md](commands.md); the recordings it writes are specified in \
               [recording-format.md](recording-format.md).",
};

fn main() -> ExitCode {
    let cli = Cli::parse();
    let result = match cli.command {
        Command::Reference => {
            print!(
                "{}",
                cli_reference::markdown(Cli::command(), &REFERENCE_PAGE)
            );
            Ok(())
        }
        Command::Suite { name, out, jobs } => run_suite(&name, &out, jobs),
        Command::UsbCamera(args) => args.options().and_then(|o| hil_sim::usb_camera::serve(&o)),
        Command::Ros2Play(args) => ros2_play(&args),
        Command::Preview { dir, at, out } => {
            let out = out.unwrap_or_else(|| dir.join("preview"));
            hil_sim::preview::write_previews(&dir, &at, &out)
                .map(|files| {
                    for f in files {
                        println!("{}", f.display());
                    }
                })
                .map_err(anyhow::Error::from)
        }
        Command::Generate {
            object,
            motion,
            speed,
            seconds,
            seed,
            out,
            drop_depth,
            noise_hz,
            no_hands,
            with,
        } => {
            let Some(object) = ObjectSource::parse(&object) else {
                let names: Vec<&str> = ObjectKind::ALL.iter().map(|k| k.name()).collect();
                eprintln!(
                    "error: unknown object `{object}`: use a library name ({}), novel:SEED, a novel object's name \
                     novel_<family>_<seed> (families: {}) or a path to an .obj file",
                    names.join(", "),
                    hil_sim::objects::NovelFamily::ALL
                        .map(|f| f.name())
                        .join(", ")
                );
                return ExitCode::FAILURE;
            };
            let mut config = GenerateConfig::new(object, motion, speed, seconds, seed);
            for (k, spec) in with.iter().enumerate() {
                match Companion::parse(spec, k + 1, motion, speed) {
                    Ok(c) => config.companions.push(c),
                    Err(e) => {
                        eprintln!("error: --with {e}");
                        return ExitCode::FAILURE;
                    }
                }
            }
            config.depth_drop_probability = drop_depth;
            config.esim.noise_rate_hz = noise_hz;
            config.hands = !no_hands;
            generate_one(&config, &out)
        }
        Command::Pattern {
            out,
            seconds,
            revolutions_per_s,
            noise_hz,
            seed,
        } => pattern(out, seconds, revolutions_per_s, noise_hz, seed),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e:#}");
            ExitCode::FAILURE
        }
    }
}

fn ros2_play(args: &hil_sim::ros2_play::args::Ros2PlayArgs) -> anyhow::Result<()> {
    let options = args.options()?;
    let s = hil_sim::ros2_play::play(&options)?;
    eprintln!(
        "ros2-play: published {} event packets ({} bytes) and {} depth frames ({} stamped by the schedule), \
         {:.3} s of stream in {:.3} s; stamp offset {} ns",
        s.packets,
        s.bytes,
        s.depth_frames,
        s.depth_from_schedule,
        s.stream_seconds,
        s.wall_seconds,
        s.stamp_offset_ns
    );
    Ok(())
}

fn run_suite(name: &str, out: &std::path::Path, jobs: Option<u32>) -> anyhow::Result<()> {
    let Some(entries) = hil_sim::suite::suite(name) else {
        anyhow::bail!(
            "unknown suite `{name}` (known: {})",
            hil_sim::suite::SUITES.join(", ")
        );
    };
    let jobs = jobs.map_or_else(
        || std::thread::available_parallelism().map_or(1, usize::from),
        |j| j as usize,
    );
    let total: f64 = entries.iter().map(|e| e.config.seconds).sum();
    let bar =
        ProgressBar::with_draw_target(Some((total * 1000.0) as u64), ProgressDrawTarget::stderr());
    bar.set_style(
        ProgressStyle::with_template(
            "{msg} [{bar:30}] {pos}/{len} ms simulated, {elapsed} elapsed, eta {eta}",
        )
        .unwrap_or_else(|_| ProgressStyle::default_bar())
        .progress_chars("=> "),
    );
    bar.set_message(format!("{} jobs", jobs.min(entries.len())));
    // Simulated seconds so far of each sequence (shared by the workers' callbacks).
    let simulated = std::sync::Mutex::new(vec![0.0f64; entries.len()]);
    let set = |i: usize, t: f64| {
        let mut s = simulated.lock().unwrap_or_else(|p| p.into_inner());
        s[i] = t;
        bar.set_position((s.iter().sum::<f64>() * 1000.0) as u64);
    };
    let n = entries.len();
    let mut finished = 0;
    hil_sim::suite::generate_suite(
        name,
        &entries,
        out,
        jobs,
        |i, e, report| {
            set(i, e.config.seconds);
            finished += 1;
            let what = if report.is_some() {
                "generated"
            } else {
                "reused"
            };
            bar.suspend(|| eprintln!("[{finished}/{n}] {what} {}", e.name));
        },
        set,
    )?;
    bar.finish_and_clear();
    eprintln!("suite `{name}`: {n} sequences in {}", out.display());
    Ok(())
}

fn generate_one(config: &GenerateConfig, out: &std::path::Path) -> anyhow::Result<()> {
    let bar = ProgressBar::with_draw_target(
        Some((config.seconds * 1000.0) as u64),
        ProgressDrawTarget::stderr(),
    );
    bar.set_style(
        ProgressStyle::with_template(
            "{msg} [{bar:30}] {pos}/{len} ms simulated, {elapsed} elapsed, eta {eta}",
        )
        .unwrap_or_else(|_| ProgressStyle::default_bar())
        .progress_chars("=> "),
    );
    bar.set_message(format!("generating {}", out.display()));
    let started = std::time::Instant::now();
    let report = generate(config, out, |t| bar.set_position((t * 1000.0) as u64));
    bar.finish_and_clear();
    let r = report.with_context(|| format!("generating {}", out.display()))?;
    let wall = started.elapsed().as_secs_f64();
    eprintln!(
        "wrote {}: {} events ({} signal, {} noise, {} dropped by refractoriness), {} depth frames ({} dropped), \
         {} trigger edges, {} ground-truth rows; {} renders of {:.0} px on average; {:.1} s ({:.1} s per simulated second)",
        out.display(),
        r.esim.signal_events + r.esim.noise_events,
        r.esim.signal_events,
        r.esim.noise_events,
        r.esim.refractory_dropped,
        r.depth_frames,
        r.depth_frames_dropped,
        r.trigger_edges,
        r.ground_truth_rows,
        r.renders,
        r.mean_region_px,
        wall,
        wall / config.seconds
    );
    Ok(())
}

fn pattern(out: PathBuf, seconds: f64, rev: f64, noise: f64, seed: u64) -> anyhow::Result<()> {
    anyhow::ensure!(
        seconds.is_finite() && seconds > 0.0 && seconds <= 3600.0,
        "--seconds must be in (0, 3600]"
    );
    anyhow::ensure!(
        rev.is_finite() && rev > 0.0 && rev <= 100.0,
        "--revolutions-per-s must be in (0, 100]"
    );
    anyhow::ensure!(
        noise.is_finite() && (0.0..=1000.0).contains(&noise),
        "--noise-hz must be in [0, 1000]"
    );
    let ext = out
        .extension()
        .and_then(|e| e.to_str())
        .unwrap_or("")
        .to_ascii_lowercase();
    let special = std::fs::metadata(&out).is_ok_and(|m| !m.is_file() && !m.is_dir());
    anyhow::ensure!(
        special || ext == "raw" || ext == "evt3",
        "--out {}: the pattern is an EVT 3.0 stream; name the file `.raw` (or `.evt3`)",
        out.display()
    );
    if let Some(parent) = out.parent().filter(|p| !p.as_os_str().is_empty()) {
        std::fs::create_dir_all(parent)
            .with_context(|| format!("{}: cannot create directory", parent.display()))?;
    }
    let file = File::create(&out).with_context(|| format!("{}: cannot create", out.display()))?;
    let p = RotatingBar {
        geometry: Geometry::new(1280, 720),
        seconds,
        revolutions_per_s: rev,
        noise_rate_hz: noise,
        seed,
        ..RotatingBar::default()
    };
    let stats = write_rotating_bar(&p, BufWriter::new(file))
        .with_context(|| format!("{}", out.display()))?;
    eprintln!(
        "wrote {} CD events and {} trigger edges ({seconds} s) to {}",
        stats.cd_events,
        stats.trigger_edges,
        out.display()
    );
    Ok(())
}
