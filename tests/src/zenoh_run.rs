//! A real-time run of the runtime held at its start until a test's zenoh session is connected, and the session
//! itself: what the end-to-end tests over zenoh share.

use eventtrack6d::runtime::config::Config;
use eventtrack6d::runtime::{self, Hooks, RuntimeError, StopFlag, Summary};
use std::net::TcpListener;
use std::sync::mpsc;
use std::thread::JoinHandle;
use std::time::{Duration, Instant};
use zenoh::Wait;

/// A TCP port on 127.0.0.1 that nothing listens on right now.
pub fn free_port() -> u16 {
    let l = TcpListener::bind("127.0.0.1:0").expect("bind an ephemeral port");
    l.local_addr().expect("local addr").port()
}

/// A peer session that connects to `endpoint` only: loopback, multicast scouting off.
pub fn peer_session(endpoint: &str) -> zenoh::Session {
    let mut c = zenoh::Config::default();
    let set = |c: &mut zenoh::Config, k: &str, v: &str| c.insert_json5(k, v).expect("zenoh config");
    set(&mut c, "mode", "\"peer\"");
    set(&mut c, "connect/endpoints", &format!("[\"{endpoint}\"]"));
    set(&mut c, "listen/endpoints", "[\"tcp/127.0.0.1:0\"]");
    set(&mut c, "scouting/multicast/enabled", "false");
    zenoh::open(c)
        .wait()
        .expect("open the test's zenoh session")
}

/// A run whose sinks are up and whose source waits for [`HeldRun::release`].
pub struct HeldRun {
    runner: JoinHandle<Result<Summary, RuntimeError>>,
    go: mpsc::Sender<()>,
}

impl HeldRun {
    /// Starts `config` on its own thread and returns once its sinks are up.
    pub fn start(config: Config) -> Self {
        let (ready_tx, ready_rx) = mpsc::channel::<()>();
        let (go, go_rx) = mpsc::channel::<()>();
        let hooks = Hooks {
            before_start: Some(Box::new(move || {
                let _ = ready_tx.send(());
                let _ = go_rx.recv_timeout(Duration::from_secs(60));
            })),
            stop: StopFlag::new(),
            ..Hooks::default()
        };
        let runner = std::thread::spawn(move || runtime::run(&config, hooks));
        ready_rx
            .recv_timeout(Duration::from_secs(120))
            .expect("the runtime never came up");
        Self { runner, go }
    }

    /// Waits until `session` receives the run's status puts (on `status_key`; the sessions are connected and the
    /// test's subscriptions, declared before, are known), lets them settle, and lets the source start.
    pub fn release_when_connected(&self, session: &zenoh::Session, status_key: &str) {
        let status = session
            .declare_subscriber(status_key.to_owned())
            .wait()
            .expect("subscribe to the status");
        let deadline = Instant::now() + Duration::from_secs(20);
        while status
            .recv_timeout(Duration::from_millis(100))
            .expect("status subscription")
            .is_none()
        {
            assert!(
                Instant::now() < deadline,
                "no status put reached the test's session"
            );
        }
        std::thread::sleep(Duration::from_millis(300));
        self.go.send(()).expect("the run is waiting");
    }

    /// Whether the run has ended.
    pub fn is_finished(&self) -> bool {
        self.runner.is_finished()
    }

    /// The run's summary once it ends.
    pub fn join(self) -> Result<Summary, RuntimeError> {
        self.runner.join().expect("the run's thread panicked")
    }
}
