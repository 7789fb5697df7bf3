//! Who talks to whom in a cell: the roster's services grouped into the
//! places of the picture ([`super::layout::PLACES`]), and between each two
//! places the channels one publishes and the other reads, from the ports
//! table (`phri_ipc::ports`) under the run's configuration.

use phri_config::{AudioSource, CameraSource, Config, MicSource, ServiceSpec};
use phri_ipc::ports::{self, Ports, When};

use super::layout::{spare_place, Place, PLACES, SUPERVISOR};

/// One service as the picture knows it.
#[derive(Clone, Debug, PartialEq)]
pub struct Member {
    /// its name in the roster (`control_standby`)
    pub name: String,
    /// its binary (`phri-control`)
    pub binary: String,
    /// what it publishes, in `channels::ALL` order
    pub publishes: Vec<&'static str>,
    /// what it reads, in `channels::ALL` order
    pub reads: Vec<&'static str>,
}

/// One box of the picture: a place of the layout and the services in it.
#[derive(Clone, Debug, PartialEq)]
pub struct Node {
    /// the place (its rectangle, its words)
    pub place: Place,
    /// the roster's services in it, in start order
    pub members: Vec<Member>,
    /// CPUs the first of them is pinned to (`[services.NAME] cpus`)
    pub cpus: Vec<usize>,
    /// what its services publish, in `channels::ALL` order
    pub publishes: Vec<&'static str>,
    /// what its services read, in `channels::ALL` order
    pub reads: Vec<&'static str>,
}

/// An arrow: the channels that `from` publishes and `to` reads.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Edge {
    /// index of the publishing node
    pub from: usize,
    /// index of the reading node
    pub to: usize,
    /// the channels, in `channels::ALL` order
    pub channels: Vec<&'static str>,
}

/// The cell as boxes and arrows.
#[derive(Clone, Debug, PartialEq)]
pub struct CellGraph {
    /// the boxes: the layout's places that hold a service, in [`PLACES`]
    /// order, then a spare place for each service no place names
    pub nodes: Vec<Node>,
    /// the arrows between them (none to an observer), by index into `nodes`
    pub edges: Vec<Edge>,
}

/// Whether an entry of the ports table applies to `binary` run with `args`
/// in a cell configured by `config`.
pub fn applies(when: When, binary: &str, args: &[String], config: &Config) -> bool {
    let flag = |f: &str| args.iter().any(|a| a == f);
    match when {
        When::Always => true,
        When::Flag(f) => flag(f),
        When::NoFlag(f) => !flag(f),
        When::ArmSimulated => config.robot.ip.is_empty(),
        When::ArmOutside => !config.robot.ip.is_empty(),
        When::SimulatedSource => simulated_source(binary, args, config),
        When::OtherSource => !simulated_source(binary, args, config),
    }
}

/// A camera's source is simulated (its `--camera I`, default 0); the
/// microphone's when both `[mic]` and `[audio]` are.
fn simulated_source(binary: &str, args: &[String], config: &Config) -> bool {
    match binary {
        "phri-mic" => {
            config.mic.source == MicSource::Sim && config.audio.source == AudioSource::Sim
        }
        _ => {
            let camera = args
                .windows(2)
                .find(|w| w[0] == "--camera")
                .and_then(|w| w[1].parse::<usize>().ok())
                .unwrap_or(0);
            config
                .cameras
                .get(camera)
                .is_some_and(|c| c.source == CameraSource::Sim)
        }
    }
}

/// `names` in `channels::ALL` order, once each.
fn ordered<'a>(names: impl Iterator<Item = &'a &'static str>) -> Vec<&'static str> {
    let names: Vec<&'static str> = names.copied().collect();
    phri_ipc::ALL
        .iter()
        .copied()
        .filter(|c| names.contains(c))
        .collect()
}

/// One service's ports under `config`.
fn member(name: &str, binary: &str, args: &[String], config: &Config) -> Member {
    let entries: Vec<&Ports> = ports::of(binary)
        .filter(|p| applies(p.when, binary, args, config))
        .collect();
    Member {
        name: name.into(),
        binary: binary.into(),
        publishes: ordered(entries.iter().flat_map(|p| p.publishes)),
        reads: ordered(entries.iter().flat_map(|p| p.reads)),
    }
}

impl CellGraph {
    /// The graph of `services` (the enabled ones, in start order) under
    /// `config`, with the supervisor. Services no place names get a place
    /// of their own ([`super::layout::spare_place`]).
    pub fn new(services: &[(String, ServiceSpec)], config: &Config) -> CellGraph {
        let mut all: Vec<(Member, Vec<usize>)> = services
            .iter()
            .map(|(n, s)| (member(n, &s.binary, &s.args, config), s.cpus.clone()))
            .collect();
        let supervisor = member(SUPERVISOR, "phri-supervisor", &[], config);
        all.push((supervisor, Vec::new()));
        let mut nodes: Vec<Node> = Vec::new();
        for place in PLACES {
            let members: Vec<&(Member, Vec<usize>)> = all
                .iter()
                .filter(|(m, _)| place.services.contains(&m.name.as_str()))
                .collect();
            if !members.is_empty() {
                nodes.push(node(place.clone(), &members));
            }
        }
        let placed = |n: &str| PLACES.iter().any(|p| p.services.contains(&n));
        for (k, m) in all.iter().filter(|(m, _)| !placed(&m.name)).enumerate() {
            nodes.push(node(spare_place(k, &m.0.name), &[m]));
        }
        let mut edges = Vec::new();
        for (i, a) in nodes.iter().enumerate() {
            for (j, b) in nodes.iter().enumerate() {
                if i == j || b.place.observer {
                    continue;
                }
                let channels = ordered(a.publishes.iter().filter(|c| b.reads.contains(c)));
                if !channels.is_empty() {
                    edges.push(Edge {
                        from: i,
                        to: j,
                        channels,
                    });
                }
            }
        }
        CellGraph { nodes, edges }
    }

    /// The index of the node at place `slot`.
    pub fn index(&self, slot: &str) -> Option<usize> {
        self.nodes.iter().position(|n| n.place.slot == slot)
    }

    /// Channels one service of node `i` publishes and another of it reads.
    pub fn within(&self, i: usize) -> Vec<&'static str> {
        let m = &self.nodes[i].members;
        ordered(m.iter().enumerate().flat_map(|(a, x)| {
            x.publishes.iter().filter(move |c| {
                m.iter()
                    .enumerate()
                    .any(|(b, y)| a != b && y.reads.contains(c))
            })
        }))
    }

    /// What node `i` reads that no node publishes, each with the binaries
    /// of the ports table that do (a tool: `fault/depth` from `phri-fault`).
    pub fn from_outside(&self, i: usize) -> Vec<(&'static str, Vec<&'static str>)> {
        self.nodes[i]
            .reads
            .iter()
            .filter(|c| !self.nodes.iter().any(|m| m.publishes.contains(c)))
            .map(|c| {
                let mut by: Vec<&'static str> = Vec::new();
                for p in ports::PORTS.iter().filter(|p| p.publishes.contains(c)) {
                    if !by.contains(&p.binary) {
                        by.push(p.binary);
                    }
                }
                (*c, by)
            })
            .collect()
    }
}

fn node(place: Place, members: &[&(Member, Vec<usize>)]) -> Node {
    Node {
        place,
        cpus: members.first().map(|(_, c)| c.clone()).unwrap_or_default(),
        publishes: ordered(members.iter().flat_map(|(m, _)| &m.publishes)),
        reads: ordered(members.iter().flat_map(|(m, _)| &m.reads)),
        members: members.iter().map(|(m, _)| m.clone()).collect(),
    }
}
