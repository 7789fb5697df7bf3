//! `phri-viz`: the live cell in 3-D, served over Foxglove's WebSocket
//! protocol (open `ws://127.0.0.1:8765` in Foxglove, then the layout
//! `deploy/foxglove/phri-layout.json`).
//!
//! For its owner only: a connection from another user's socket is closed
//! before a byte flows, at most `--max-clients` are served, each with an
//! outbox of `--client-buffer` MiB ([`phri_viz::server`]). When the robot's
//! state stops for `--stale-after` ms, the scene is no longer sent as current:
//! a status saying `stale` with the input's age is, until the cell returns.
//!
//! Read-only like the monitor: it subscribes to the cell's channels and never
//! publishes on one, runs under the normal scheduler, and keeps off the CPUs
//! the configuration pins the torque loop to (`[services.sim|dynamics|control]
//! cpus`) when the machine has others. Topics and what they show:
//! [`phri_viz::topics`]; messages are built only for topics a client subscribed to.

use std::collections::HashMap;
use std::error::Error;
use std::net::SocketAddr;
use std::path::PathBuf;
use std::process::ExitCode;
use std::time::{Duration, Instant};

use clap::Parser;
use phri_ipc::*;
use phri_runtime::cli::CompletionsCmd;
use phri_runtime::{now_ns, Shutdown};
use phri_viz::server::{Limits, Server};
use phri_viz::{topics, Output, Pipeline, Rates};

const BIN: &str = "phri-viz";
/// Time between two polls of the channels.
const POLL: Duration = Duration::from_millis(4);
/// Time between two attempts to subscribe to channels that do not exist yet.
const ATTACH_EVERY: Duration = Duration::from_secs(1);

/// The command line.
#[derive(Parser, Debug)]
#[command(
    version = phri_runtime::cli::VERSION,
    about = "Serves the live cell in 3-D over Foxglove's WebSocket protocol: robot and person capsules, depth, repulsion, collaboration, joint states, residual, mode and phase (read-only)",
    args_conflicts_with_subcommands = true
)]
struct Cli {
    /// iceoryx2 prefix of the cell [default: phri_]
    #[arg(long, value_name = "PREFIX", env = phri_runtime::PREFIX_ENV)]
    prefix: Option<String>,
    /// Cell configuration (TOML): the robot model, the residual's thresholds, the control points' names, the torque loop's CPUs
    #[arg(long, value_name = "FILE", default_value = "deploy/phri.toml")]
    config: PathBuf,
    /// Address the WebSocket server listens on (port 0: any free port)
    #[arg(long, value_name = "HOST:PORT", default_value = "127.0.0.1:8765")]
    addr: SocketAddr,
    /// Scene rate: capsules, vectors, frames, depth cloud and image [Hz]
    #[arg(long, value_name = "HZ", default_value_t = 30.0)]
    rate: f64,
    /// Joint-state and status rate [Hz] (at or above the robot's rate: every state)
    #[arg(long, value_name = "HZ", default_value_t = 250.0)]
    joint_rate: f64,
    /// Keep every K-th depth pixel per axis in the depth image
    #[arg(long, value_name = "K", default_value_t = 2, value_parser = clap::value_parser!(u32).range(1..=64))]
    depth_downsample: u32,
    /// Keep every K-th depth pixel per axis in the point cloud
    #[arg(long, value_name = "K", default_value_t = 4, value_parser = clap::value_parser!(u32).range(1..=64))]
    cloud_downsample: u32,
    /// Clients served at once (another is answered 503); only this user's (and root's) are admitted
    #[arg(long, value_name = "N", default_value_t = 4, value_parser = clap::value_parser!(u32).range(1..=64))]
    max_clients: u32,
    /// Messages waiting for one client, at most [MiB]: a slower client loses the oldest
    #[arg(long, value_name = "MIB", default_value_t = 8, value_parser = clap::value_parser!(u32).range(1..=1024))]
    client_buffer: u32,
    /// No robot state for this long [ms]: the scene is stale (not sent; the status says stale and the age)
    #[arg(long, value_name = "MS", default_value_t = 500, value_parser = clap::value_parser!(u32).range(10..=600_000))]
    stale_after: u32,
    #[command(subcommand)]
    completions: Option<CompletionsCmd>,
}

fn main() -> ExitCode {
    let cli: Cli = phri_runtime::cli::parse(BIN);
    if let Some(CompletionsCmd::Completions { shell }) = cli.completions {
        phri_runtime::cli::completions::<Cli>(BIN, shell);
        return ExitCode::SUCCESS;
    }
    let prefix = phri_runtime::prefix_or_default(cli.prefix.as_deref().filter(|p| !p.is_empty()));
    let code = phri_runtime::service::run(BIN, || body(cli).map_err(|e| e.to_string()));
    // the last node out of the prefix takes back what iceoryx2 left
    let _ = phri_ipc::remove_leftovers(&prefix);
    code
}

fn rate(flag: &str, hz: f64) -> Result<f64, String> {
    if hz.is_finite() && hz > 0.0 && hz <= 10_000.0 {
        Ok(hz)
    } else {
        Err(format!("{flag} {hz}: must be a rate in (0, 10000] Hz"))
    }
}

/// One channel the scene is made of: subscribed once it exists.
trait Source {
    fn name(&self) -> &'static str;
    /// subscribe if the channel exists now (a viewer never creates one)
    fn attach(&mut self, node: &IpcNode) -> Result<bool, IpcError>;
    /// hand what arrived to the pipeline
    fn poll(
        &mut self,
        p: &mut Pipeline,
        wanted: &dyn Fn(&str) -> bool,
        out: &mut Vec<Output>,
    ) -> Result<(), IpcError>;
}

struct Messages<T: Message> {
    channel: Channel<T>,
    queue: Queue,
    sub: Option<Subscriber<T>>,
}

impl<T: Message> Messages<T> {
    fn boxed(channel: Channel<T>, queue: Queue) -> Box<dyn Source> {
        Box::new(Messages {
            channel,
            queue,
            sub: None,
        })
    }
}

impl<T: Message> Source for Messages<T> {
    fn name(&self) -> &'static str {
        self.channel.name
    }
    fn attach(&mut self, node: &IpcNode) -> Result<bool, IpcError> {
        if self.sub.is_none() {
            self.sub = self.channel.subscriber_if_exists(node, self.queue)?;
        }
        Ok(self.sub.is_some())
    }
    fn poll(
        &mut self,
        p: &mut Pipeline,
        wanted: &dyn Fn(&str) -> bool,
        out: &mut Vec<Output>,
    ) -> Result<(), IpcError> {
        if let Some(sub) = &self.sub {
            sub.drain(|m| p.offer(m, wanted, out))?;
        }
        Ok(())
    }
}

/// The filtered depth: only the newest frame, its depths copied only when a
/// client wants the cloud or the image.
struct Frames {
    sub: Option<FrameSubscriber>,
}

impl Source for Frames {
    fn name(&self) -> &'static str {
        PERCEPTION_DEPTH.name
    }
    fn attach(&mut self, node: &IpcNode) -> Result<bool, IpcError> {
        if self.sub.is_none() {
            self.sub = PERCEPTION_DEPTH.frame_subscriber_if_exists(node, Queue::Latest)?;
        }
        Ok(self.sub.is_some())
    }
    fn poll(
        &mut self,
        p: &mut Pipeline,
        wanted: &dyn Fn(&str) -> bool,
        out: &mut Vec<Output>,
    ) -> Result<(), IpcError> {
        let Some(sub) = &self.sub else {
            return Ok(());
        };
        if let Some(f) = sub.latest()? {
            if wanted(topics::POINTS) || wanted(topics::IMAGE) {
                p.offer_frame(f.user_header(), f.payload());
            } else {
                p.offer(f.user_header(), wanted, out);
            }
        }
        Ok(())
    }
}

fn sources() -> Vec<Box<dyn Source>> {
    vec![
        // every state: the joint rate is counted on the robot's clock
        Messages::boxed(ROBOT_STATE, Queue::Drain),
        Messages::boxed(DYNAMICS_RESIDUAL, Queue::Latest),
        Messages::boxed(CONTROL_STATUS, Queue::Latest),
        Messages::boxed(COLLAB_STATE, Queue::Latest),
        Messages::boxed(SIM_WORLD, Queue::Latest),
        // one result per worker per frame
        Messages::boxed(PERCEPTION_REPULSION, Queue::Drain),
        Messages::boxed(PERCEPTION_HAND, Queue::Latest),
        Box::new(Frames { sub: None }),
    ]
}

fn body(cli: Cli) -> Result<(), Box<dyn Error>> {
    let rates = Rates {
        scene_hz: rate("--rate", cli.rate)?,
        joints_hz: rate("--joint-rate", cli.joint_rate)?,
        depth_downsample: cli.depth_downsample as usize,
        cloud_downsample: cli.cloud_downsample as usize,
    };
    let prefix = phri_runtime::prefix_or_default(cli.prefix.as_deref().filter(|p| !p.is_empty()));
    let loaded = phri_config::Loaded::load(&cli.config, None, &[])
        .map_err(|e| format!("--config {}: {e}", cli.config.display()))?;
    let mut pipeline = Pipeline::from_config(&loaded, rates)
        .map_err(|e| format!("--config {}: {e}", cli.config.display()))?
        .with_stale_after(Some(Duration::from_millis(u64::from(cli.stale_after))));
    phri_runtime::placement::keep_off_the_loop(&loaded.config);

    let shutdown = Shutdown::install()?;
    let limits = Limits {
        max_clients: cli.max_clients as usize,
        queue_bytes: cli.client_buffer as usize * (1 << 20),
    };
    let server = Server::start(cli.addr, BIN, &topics::all(), limits)
        .map_err(|e| format!("--addr {}: cannot serve: {e}", cli.addr))?;
    let port = server.local_addr().port();
    // the line a script (or a test) waits for: the port actually bound
    eprintln!(
        "{BIN}: serving ws://{}:{port} (prefix '{prefix}')",
        cli.addr.ip()
    );

    let node = node(&format!("viz{}", std::process::id()), &prefix)?;
    let mut sources = sources();
    let mut attached = vec![false; sources.len()];
    let mut next_attach = Instant::now();
    let mut out: Vec<Output> = Vec::new();
    let mut buf: Vec<u8> = Vec::new();
    let mut sent: HashMap<&'static str, u64> = HashMap::new();
    let mut next_report = Instant::now() + Duration::from_secs(10);
    let mut reported_at = Instant::now();
    let mut was_stale = false;
    while !shutdown.requested() {
        if Instant::now() >= next_attach {
            for (s, a) in sources.iter_mut().zip(attached.iter_mut()) {
                if !*a && s.attach(&node)? {
                    *a = true;
                    tracing::info!("subscribed to {}", s.name());
                }
            }
            next_attach = Instant::now() + ATTACH_EVERY;
        }
        let wanted = |topic: &str| server.wanted(topic);
        for s in sources.iter_mut() {
            s.poll(&mut pipeline, &wanted, &mut out)?;
        }
        let now = now_ns();
        pipeline.tick(now, &wanted, &mut out);
        if pipeline.is_stale() != was_stale {
            was_stale = pipeline.is_stale();
            match pipeline.input_age_ns(now) {
                Some(age) if was_stale => tracing::warn!(
                    "no robot state for {:.1} s: the scene is stale",
                    age as f64 * 1e-9
                ),
                None => tracing::info!("no robot state yet: the scene is stale"),
                Some(_) => tracing::info!("robot state again: the scene is live"),
            }
        }
        for o in out.drain(..) {
            buf.clear();
            match o.message.encode(&mut buf) {
                Ok(()) => {
                    server.publish(o.topic, o.log_ns, &buf);
                    *sent.entry(o.topic).or_default() += 1;
                }
                Err(e) => tracing::warn!("{}: {e}", o.topic),
            }
        }
        if Instant::now() >= next_report {
            let dt = reported_at.elapsed().as_secs_f64();
            let mut rates: Vec<String> = sent
                .iter()
                .map(|(t, n)| format!("{t} {:.1}/s", *n as f64 / dt))
                .collect();
            rates.sort();
            if rates.is_empty() {
                rates.push("nothing subscribed".into());
            }
            let c = server.counts();
            tracing::info!(
                "{} client(s); {}; refused {} of another user, {} over --max-clients; {} dropped for slow clients",
                c.clients,
                rates.join(", "),
                c.refused_user,
                c.refused_full,
                c.dropped
            );
            sent.clear();
            reported_at = Instant::now();
            next_report += Duration::from_secs(10);
        }
        std::thread::sleep(POLL);
    }
    server.stop();
    Ok(())
}
