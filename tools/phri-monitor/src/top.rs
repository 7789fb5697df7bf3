//! `phri-monitor top`: the dashboard's state ([`TopState`]), its drawing
//! ([`render`], pure: the same state draws the same cells, so a test draws it
//! into ratatui's `TestBackend`) and its keys ([`on_key`], pure over the
//! state). The probes that fill the state live in `main.rs`.

use std::collections::VecDeque;

use phri_ipc::{residual_flags, ControlMode, SUPERVISOR_HEALTH};
use ratatui::buffer::Buffer;
use ratatui::crossterm::event::{KeyCode, KeyEvent, KeyEventKind, KeyModifiers};
use ratatui::layout::{Constraint, Layout, Rect};
use ratatui::style::{Color, Modifier, Style};
use ratatui::symbols::Marker;
use ratatui::text::{Line, Span};
use ratatui::widgets::{
    Axis, Block, Borders, Cell, Chart, Dataset, GraphType, Paragraph, Row, StatefulWidget, Table,
    TableState, Widget, Wrap,
};
use serde_json::Value;

/// Span of the plots' history \[s\].
pub const HISTORY_S: f64 = 30.0;
/// A stream is stale when its newest sample is older than this many of its
/// mean intervals ...
const STALE_INTERVALS: f64 = 5.0;
/// ... and at least this old \[ms\] (a 1 kHz stream is not stale after 5 ms).
const STALE_FLOOR_MS: f64 = 250.0;
/// Age after which a stream too slow to have a mean interval in the 1 s
/// window (under 2 Hz) is stale \[ms\].
const STALE_SLOW_MS: f64 = 3000.0;
/// Width of the services pane beside the channels \[columns\].
const SERVICES_W: u16 = 44;
/// Channel pane width from which every column shows \[columns\].
const FULL_TABLE_W: u16 = 104;

/// How current a channel's traffic is.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Freshness {
    /// samples arrive at the stream's own pace
    Fresh,
    /// a stream that should flow stopped: newest sample too old (red)
    Stale,
    /// the channel exists but nothing was ever seen on it (yellow)
    Silent,
    /// an on-demand channel with nothing recent (normal)
    Idle,
    /// the channel does not exist under the prefix
    Absent,
}

impl Freshness {
    /// A channel's freshness from its figures: `age_ms` of its newest sample
    /// and `mean_ms` interval over the window \[ms\], both unknown when not seen.
    pub fn of(
        present: bool,
        on_demand: bool,
        age_ms: Option<f64>,
        mean_ms: Option<f64>,
    ) -> Freshness {
        if !present {
            return Freshness::Absent;
        }
        match (age_ms, on_demand) {
            (None, true) => Freshness::Idle,
            (None, false) => Freshness::Silent,
            (Some(_), true) => Freshness::Fresh,
            (Some(age), false) => {
                let limit =
                    mean_ms.map_or(STALE_SLOW_MS, |m| (STALE_INTERVALS * m).max(STALE_FLOOR_MS));
                if age > limit {
                    Freshness::Stale
                } else {
                    Freshness::Fresh
                }
            }
        }
    }

    fn label(self) -> &'static str {
        match self {
            Freshness::Fresh => "ok",
            Freshness::Stale => "STALE",
            Freshness::Silent => "silent",
            Freshness::Idle => "idle",
            Freshness::Absent => "absent",
        }
    }

    fn style(self) -> Style {
        match self {
            Freshness::Fresh | Freshness::Idle => Style::default(),
            Freshness::Stale => Style::default().fg(Color::Red).add_modifier(Modifier::BOLD),
            Freshness::Silent => Style::default().fg(Color::Yellow),
            Freshness::Absent => Style::default().fg(Color::DarkGray),
        }
    }
}

/// One channel's figures over the last window (1 s), as `list --json` gives them.
#[derive(Clone, Debug, PartialEq)]
pub struct ChannelRow {
    pub name: &'static str,
    pub present: bool,
    pub publishers: u64,
    /// subscribers other than this monitor
    pub subscribers: u64,
    /// samples per second over the window \[Hz\]
    pub rate_hz: f64,
    /// mean and largest interval between samples \[ms\]
    pub mean_ms: Option<f64>,
    pub max_ms: Option<f64>,
    /// age of the newest sample \[ms\]: since it was published, else (messages
    /// without a publish time) since it was received
    pub age_ms: Option<f64>,
    /// [bytes/s]
    pub bandwidth_bps: f64,
    /// sequence gaps since the monitor attached
    pub drops: u64,
    pub freshness: Freshness,
}

impl ChannelRow {
    /// The row of channel `name` from its JSON figures (`present`,
    /// `publishers`, `subscribers` and the probe's summary); `known_mean_ms`:
    /// the stream's mean interval when last measured \[ms\], which judges its
    /// age once the window holds no interval any more; `recv_age_ms`: time
    /// since the newest sample was received \[ms\], the age of messages
    /// without a publish time.
    pub fn from_json(
        name: &'static str,
        v: &Value,
        on_demand: bool,
        known_mean_ms: Option<f64>,
        recv_age_ms: Option<f64>,
    ) -> ChannelRow {
        let f = |k: &str| v.get(k).and_then(Value::as_f64);
        let u = |k: &str| v.get(k).and_then(Value::as_u64).unwrap_or(0);
        let present = v.get("present").and_then(Value::as_bool).unwrap_or(false);
        let (age_ms, mean_ms) = (f("age_ms").or(recv_age_ms), f("mean_interval_ms"));
        ChannelRow {
            name,
            present,
            publishers: u("publishers"),
            subscribers: u("subscribers"),
            rate_hz: f("rate_hz").unwrap_or(0.0),
            mean_ms,
            max_ms: f("max_interval_ms"),
            age_ms,
            bandwidth_bps: f("bandwidth_bps").unwrap_or(0.0),
            drops: u("total_drops"),
            freshness: Freshness::of(present, on_demand, age_ms, mean_ms.or(known_mean_ms)),
        }
    }
}

/// One service as the supervisor's health reports it, with its CPU use.
#[derive(Clone, Debug, PartialEq)]
pub struct ServiceRow {
    pub name: String,
    pub pid: i32,
    pub alive: bool,
    pub restarts: u32,
    /// share of one core over the last seconds (`None`: not measured yet)
    pub cpu_share: Option<f64>,
    /// its `[services.NAME] cpu_budget` in the run's configuration
    pub cpu_budget: Option<f64>,
}

impl ServiceRow {
    /// It uses more of a core than its budget.
    pub fn over_budget(&self) -> bool {
        matches!((self.cpu_share, self.cpu_budget), (Some(s), Some(b)) if s > b)
    }
}

/// Processes' shares of one core from their CPU time, smoothed over about a
/// second of refreshes.
#[derive(Clone, Debug, Default)]
pub struct CpuMeter {
    /// per pid: (when \[s\], its CPU time then \[ns\], its smoothed share)
    seen: std::collections::HashMap<i32, (f64, u64, Option<f64>)>,
}

impl CpuMeter {
    /// Process `pid` had used `cpu_ns` at `t_s`: its share of one core
    /// (`None` until two samples 0.2 s or more apart).
    pub fn share(&mut self, pid: i32, t_s: f64, cpu_ns: u64) -> Option<f64> {
        let entry = self.seen.entry(pid).or_insert((t_s, cpu_ns, None));
        let (t0, c0, smoothed) = *entry;
        if t_s - t0 < 0.2 {
            return smoothed;
        }
        let share = cpu_ns.saturating_sub(c0) as f64 * 1e-9 / (t_s - t0);
        let s = smoothed.map_or(share, |old| old + 0.3 * (share - old));
        *entry = (t_s, cpu_ns, Some(s));
        Some(s)
    }

    /// Forget the processes not in `pids` (gone, restarted under another pid).
    pub fn keep_only(&mut self, pids: &[i32]) {
        self.seen.retain(|pid, _| pids.contains(pid));
    }
}

/// The cell's newest values (`None`: no message yet).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Snapshot {
    /// the controller's mode ([`ControlMode`] name)
    pub mode: Option<&'static str>,
    /// smallest obstacle distance of the control points \[m\]
    pub min_distance: Option<f64>,
    /// ‖r‖ of the momentum residual \[Nm\]
    pub residual_norm: Option<f64>,
    /// [`residual_flags`] of the newest residual
    pub residual_flags: u32,
    /// the collaboration's phase name
    pub collab_phase: Option<&'static str>,
    /// F̂ of the collaborative contact \[N\], base frame
    pub contact_force: Option<[f64; 3]>,
    /// the robot's brakes are engaged
    pub braking: bool,
    /// the supervisor's health has been heard
    pub health_seen: bool,
}

/// A time series of the plots: (t [s since the monitor started], value).
#[derive(Clone, Debug, Default)]
pub struct Series(pub VecDeque<(f64, f64)>);

impl Series {
    /// Append a point (non-finite values are gaps: left out) and forget
    /// points older than [`HISTORY_S`].
    pub fn push(&mut self, t: f64, x: f64) {
        if x.is_finite() {
            self.0.push_back((t, x));
        }
        while self.0.front().is_some_and(|&(t0, _)| t0 < t - HISTORY_S) {
            self.0.pop_front();
        }
    }

    fn bounds(&self) -> Option<[f64; 2]> {
        let (lo, hi) = self
            .0
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), &(_, x)| {
                (l.min(x), h.max(x))
            });
        (lo <= hi).then_some([lo, hi])
    }
}

/// The live plots' histories.
#[derive(Clone, Debug, Default)]
pub struct History {
    /// smallest obstacle distance \[m\]
    pub distance: Series,
    /// ‖r‖ \[Nm\]
    pub residual: Series,
    /// applied joint torque per joint \[Nm\] (`robot/state` τ)
    pub torque: Vec<Series>,
}

/// Order of the channels table (`s` cycles through them).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum SortBy {
    /// the cell's order of channels
    #[default]
    Cell,
    Name,
    /// fastest first
    Rate,
    /// oldest newest-sample first (stale on top)
    Age,
    /// most drops first
    Drops,
}

impl SortBy {
    fn next(self) -> SortBy {
        match self {
            SortBy::Cell => SortBy::Name,
            SortBy::Name => SortBy::Rate,
            SortBy::Rate => SortBy::Age,
            SortBy::Age => SortBy::Drops,
            SortBy::Drops => SortBy::Cell,
        }
    }

    fn label(self) -> &'static str {
        match self {
            SortBy::Cell => "cell order",
            SortBy::Name => "name",
            SortBy::Rate => "rate",
            SortBy::Age => "age",
            SortBy::Drops => "drops",
        }
    }
}

/// What the main pane shows.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum View {
    #[default]
    Channels,
    /// the newest message of a channel, as `echo` prints it
    Echo(&'static str),
}

/// Everything the dashboard draws.
#[derive(Clone, Debug, Default)]
pub struct TopState {
    pub prefix: String,
    /// time since the monitor started \[s\]
    pub t_s: f64,
    pub snapshot: Snapshot,
    /// in the cell's order
    pub channels: Vec<ChannelRow>,
    pub services: Vec<ServiceRow>,
    pub history: History,
    pub sort: SortBy,
    /// the selected channel (kept by name across sorting and refreshes)
    pub selected: Option<&'static str>,
    pub view: View,
    /// newest message of the echoed channel, as JSON (`None`: none yet)
    pub echo: Option<Value>,
}

impl TopState {
    pub fn new(prefix: &str) -> TopState {
        TopState {
            prefix: prefix.to_string(),
            ..Default::default()
        }
    }

    /// The channels in the table's order.
    pub fn sorted(&self) -> Vec<&ChannelRow> {
        let mut rows: Vec<&ChannelRow> = self.channels.iter().collect();
        let age = |r: &ChannelRow| {
            r.age_ms
                .unwrap_or(if r.present { f64::INFINITY } else { -1.0 })
        };
        match self.sort {
            SortBy::Cell => {}
            SortBy::Name => rows.sort_by(|a, b| a.name.cmp(b.name)),
            SortBy::Rate => rows.sort_by(|a, b| b.rate_hz.total_cmp(&a.rate_hz)),
            SortBy::Age => rows.sort_by(|a, b| age(b).total_cmp(&age(a))),
            SortBy::Drops => rows.sort_by_key(|r| std::cmp::Reverse(r.drops)),
        }
        rows
    }

    /// Index of the selected channel in the table's order.
    fn selected_index(&self) -> Option<usize> {
        let name = self.selected?;
        self.sorted().iter().position(|r| r.name == name)
    }

    /// What needs attention, worst first: (alarm = red, else warning = yellow, text).
    pub fn alarms(&self) -> Vec<(bool, String)> {
        let s = &self.snapshot;
        let mut out = Vec::new();
        if s.braking {
            out.push((true, "robot braking".to_string()));
        }
        match s.mode.map(mode_severity) {
            Some(Severity::Alarm) => out.push((true, format!("mode {}", s.mode.unwrap_or("-")))),
            Some(Severity::Warn) => out.push((false, format!("mode {}", s.mode.unwrap_or("-")))),
            _ => {}
        }
        if s.residual_flags & residual_flags::COLLISION != 0 {
            out.push((true, "collision detected".to_string()));
        } else if s.residual_flags & residual_flags::CONTACT != 0 {
            out.push((false, "contact".to_string()));
        }
        for sv in &self.services {
            if !sv.alive {
                out.push((true, format!("{} down", sv.name)));
            } else if sv.restarts > 0 {
                out.push((false, format!("{} restarted {}×", sv.name, sv.restarts)));
            }
        }
        let names = |f: Freshness| {
            self.channels
                .iter()
                .filter(|c| c.freshness == f)
                .map(|c| c.name)
                .collect::<Vec<_>>()
        };
        let stale = names(Freshness::Stale);
        if !stale.is_empty() {
            out.push((true, format!("stale: {}", stale.join(", "))));
        }
        let silent = names(Freshness::Silent);
        if !silent.is_empty() {
            out.push((false, format!("silent: {}", silent.join(", "))));
        }
        if !s.health_seen {
            out.push((false, "no supervisor health".to_string()));
        }
        out.sort_by_key(|(alarm, _)| !alarm);
        out
    }
}

#[derive(Clone, Copy, PartialEq, Eq)]
enum Severity {
    Normal,
    Warn,
    Alarm,
}

/// How a controller mode is shown: a reaction or a protective stop is an
/// alarm, a slowed or recovering or backing-off robot a warning.
fn mode_severity(mode: &str) -> Severity {
    match ControlMode::from_name(mode) {
        Ok(ControlMode::Reaction | ControlMode::ProtectiveStop) => Severity::Alarm,
        Ok(ControlMode::Slow | ControlMode::Recover | ControlMode::BackOff) => Severity::Warn,
        _ => Severity::Normal,
    }
}

/// What the loop does after a key.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum KeyOutcome {
    Continue,
    Quit,
}

/// Apply one key to the state: `q`, Ctrl-C, Esc (on the table) quit; `s`
/// cycles the sort; Up/Down (or `k`/`j`) select a channel; Enter shows the
/// selected channel's newest message; Esc goes back to the table.
pub fn on_key(st: &mut TopState, key: KeyEvent) -> KeyOutcome {
    if key.kind != KeyEventKind::Press {
        return KeyOutcome::Continue;
    }
    let ctrl = key.modifiers.contains(KeyModifiers::CONTROL);
    match key.code {
        KeyCode::Char('c') if ctrl => return KeyOutcome::Quit,
        KeyCode::Char('q') => return KeyOutcome::Quit,
        KeyCode::Esc => match st.view {
            View::Channels => return KeyOutcome::Quit,
            View::Echo(_) => {
                st.view = View::Channels;
                st.echo = None;
            }
        },
        KeyCode::Char('s') => st.sort = st.sort.next(),
        KeyCode::Up | KeyCode::Char('k') => move_selection(st, -1),
        KeyCode::Down | KeyCode::Char('j') => move_selection(st, 1),
        KeyCode::Enter => {
            if st.selected.is_none() {
                move_selection(st, 1);
            }
            if let Some(name) = st.selected {
                if st.view != View::Echo(name) {
                    st.echo = None;
                }
                st.view = View::Echo(name);
            }
        }
        _ => {}
    }
    KeyOutcome::Continue
}

fn move_selection(st: &mut TopState, step: isize) {
    let names: Vec<&'static str> = st.sorted().iter().map(|r| r.name).collect();
    if names.is_empty() {
        return;
    }
    let next = match st.selected_index() {
        None => 0,
        Some(i) => i.saturating_add_signed(step).min(names.len() - 1),
    };
    st.selected = Some(names[next]);
    // the echo pane follows the selection
    if let View::Echo(name) = st.view {
        if name != names[next] {
            st.view = View::Echo(names[next]);
            st.echo = None;
        }
    }
}

/// The fields of a message as `echo` prints them (`key=value`, in order).
pub fn echo_fields(v: &Value) -> Vec<String> {
    match v {
        Value::Object(m) => m.iter().map(|(k, v)| format!("{k}={v}")).collect(),
        other => vec![other.to_string()],
    }
}

/// Draw the whole dashboard into `area` of `buf`.
pub fn render(st: &TopState, area: Rect, buf: &mut Buffer) {
    let plots_h = (area.height / 3).clamp(6, 16);
    let [head, body, plots] = Layout::vertical([
        Constraint::Length(3),
        Constraint::Min(6),
        Constraint::Length(plots_h),
    ])
    .areas(area);
    render_header(st, head, buf);
    let services_h = st.services.len() as u16 + 3;
    let (main, side) = if body.width >= 64 + SERVICES_W {
        let [m, s] =
            Layout::horizontal([Constraint::Min(40), Constraint::Length(SERVICES_W)]).areas(body);
        (m, s)
    } else {
        let [m, s] = Layout::vertical([
            Constraint::Min(4),
            Constraint::Length(services_h.min(body.height / 2)),
        ])
        .areas(body);
        (m, s)
    };
    match st.view {
        View::Channels => render_channels(st, main, buf),
        View::Echo(name) => render_echo(st, name, main, buf),
    }
    render_services(st, side, buf);
    render_plots(st, plots, buf);
}

fn render_header(st: &TopState, area: Rect, buf: &mut Buffer) {
    let s = &st.snapshot;
    let dim = Style::default().fg(Color::DarkGray);
    let title = Line::from(vec![
        Span::styled(
            "phri-monitor top",
            Style::default().add_modifier(Modifier::BOLD),
        ),
        Span::raw(format!("  prefix '{}'  t {:.1} s", st.prefix, st.t_s)),
        Span::styled(
            "   q quit · s sort · ↑↓ select · Enter echo · Esc back",
            dim,
        ),
    ]);
    let mode_style = match s.mode.map(mode_severity) {
        Some(Severity::Alarm) => Style::default().fg(Color::Red).add_modifier(Modifier::BOLD),
        Some(Severity::Warn) => Style::default()
            .fg(Color::Yellow)
            .add_modifier(Modifier::BOLD),
        Some(Severity::Normal) => Style::default()
            .fg(Color::Green)
            .add_modifier(Modifier::BOLD),
        None => dim,
    };
    let force = s.contact_force.map_or("-".into(), |f| {
        let n = (f[0] * f[0] + f[1] * f[1] + f[2] * f[2]).sqrt();
        format!("{n:.1} N [{:.1}, {:.1}, {:.1}]", f[0], f[1], f[2])
    });
    let values = Line::from(vec![
        Span::raw("mode "),
        Span::styled(s.mode.unwrap_or("-"), mode_style),
        Span::raw(format!(
            "   min distance {}   residual ‖r‖ {}   collaboration {}   F̂ {}",
            s.min_distance.map_or("-".into(), |d| format!("{d:.3} m")),
            s.residual_norm.map_or("-".into(), |n| format!("{n:.2} Nm")),
            s.collab_phase.unwrap_or("-"),
            force
        )),
    ]);
    let alarms = st.alarms();
    let alarm_line = if alarms.is_empty() {
        Line::from(Span::styled("no alarms", Style::default().fg(Color::Green)))
    } else {
        let mut spans = Vec::new();
        for (i, (alarm, text)) in alarms.into_iter().enumerate() {
            if i > 0 {
                spans.push(Span::raw(" · "));
            }
            let style = if alarm {
                Style::default().fg(Color::Red).add_modifier(Modifier::BOLD)
            } else {
                Style::default().fg(Color::Yellow)
            };
            spans.push(Span::styled(text, style));
        }
        Line::from(spans)
    };
    Paragraph::new(vec![title, values, alarm_line]).render(area, buf);
}

/// A share as a percentage (`–`: none).
fn percent(x: Option<f64>) -> String {
    x.map_or("–".to_string(), |v| format!("{:.1}%", 100.0 * v))
}

fn opt(x: Option<f64>, digits: usize) -> String {
    x.map_or("-".into(), |x| format!("{x:.digits$}"))
}

/// Bandwidth for people: B/s, kB/s, MB/s.
pub fn human_bandwidth(bps: f64) -> String {
    if bps >= 1e6 {
        format!("{:.1} MB/s", bps / 1e6)
    } else if bps >= 1e3 {
        format!("{:.1} kB/s", bps / 1e3)
    } else {
        format!("{bps:.0} B/s")
    }
}

fn render_channels(st: &TopState, area: Rect, buf: &mut Buffer) {
    let full = area.width >= FULL_TABLE_W;
    let mut head = vec!["channel", "pub", "sub", "rate Hz"];
    let mut widths = vec![
        Constraint::Length(22),
        Constraint::Length(3),
        Constraint::Length(3),
        Constraint::Length(8),
    ];
    if full {
        head.extend(["mean ms", "max ms"]);
        widths.extend([Constraint::Length(8), Constraint::Length(8)]);
    }
    head.push("age ms");
    widths.push(Constraint::Length(9));
    if full {
        head.push("bandwidth");
        widths.push(Constraint::Length(10));
    }
    head.extend(["drops", "state"]);
    widths.extend([Constraint::Length(6), Constraint::Length(6)]);
    let rows = st.sorted().into_iter().map(|c| {
        let mut cells = vec![Cell::from(c.name)];
        if c.present {
            cells.extend([
                Cell::from(format!("{:>3}", c.publishers)),
                Cell::from(format!("{:>3}", c.subscribers)),
                Cell::from(format!("{:>8.1}", c.rate_hz)),
            ]);
            if full {
                cells.push(Cell::from(format!("{:>8}", opt(c.mean_ms, 3))));
                cells.push(Cell::from(format!("{:>8}", opt(c.max_ms, 3))));
            }
            cells.push(Cell::from(format!("{:>9}", opt(c.age_ms, 2))));
            if full {
                cells.push(Cell::from(format!(
                    "{:>10}",
                    human_bandwidth(c.bandwidth_bps)
                )));
            }
            cells.push(Cell::from(format!("{:>6}", c.drops)).style(if c.drops > 0 {
                Style::default().fg(Color::Yellow)
            } else {
                Style::default()
            }));
        } else {
            let n = if full { 8 } else { 5 };
            cells.extend((0..n).map(|_| Cell::from("")));
        }
        cells.push(Cell::from(c.freshness.label()));
        Row::new(cells).style(c.freshness.style())
    });
    let table = Table::new(rows, widths)
        .header(
            Row::new(head)
                .style(Style::default().add_modifier(Modifier::BOLD | Modifier::UNDERLINED)),
        )
        .row_highlight_style(Style::default().add_modifier(Modifier::REVERSED))
        .highlight_symbol("▶ ")
        .block(Block::default().borders(Borders::ALL).title(format!(
            " channels (1 s window, sort: {}) ",
            st.sort.label()
        )));
    let mut ts = TableState::default().with_selected(st.selected_index());
    StatefulWidget::render(table, area, buf, &mut ts);
}

fn render_echo(st: &TopState, name: &str, area: Rect, buf: &mut Buffer) {
    let lines: Vec<Line> = match &st.echo {
        Some(v) => echo_fields(v).into_iter().map(Line::from).collect(),
        None => vec![Line::styled(
            "(no message yet)",
            Style::default().fg(Color::DarkGray),
        )],
    };
    Paragraph::new(lines)
        .wrap(Wrap { trim: false })
        .block(
            Block::default()
                .borders(Borders::ALL)
                .title(format!(" echo {name}: newest message (Esc back) ")),
        )
        .render(area, buf);
}

fn render_services(st: &TopState, area: Rect, buf: &mut Buffer) {
    let rows = st.services.iter().map(|s| {
        let (alive, style) = if !s.alive {
            (
                "NO",
                Style::default().fg(Color::Red).add_modifier(Modifier::BOLD),
            )
        } else if s.over_budget() {
            ("yes", Style::default().fg(Color::Red))
        } else if s.restarts > 0 {
            ("yes", Style::default().fg(Color::Yellow))
        } else {
            ("yes", Style::default().fg(Color::Green))
        };
        Row::new(vec![
            Cell::from(s.name.clone()),
            Cell::from(format!("{:>7}", s.pid)),
            Cell::from(alive),
            Cell::from(format!("{:>8}", s.restarts)),
            Cell::from(format!("{:>6}", percent(s.cpu_share))),
            Cell::from(format!("{:>6}", percent(s.cpu_budget))),
        ])
        .style(style)
    });
    // the supervisor's health gone stale: the rows are the last known
    let health_stale = st
        .channels
        .iter()
        .any(|c| c.name == SUPERVISOR_HEALTH.name && c.freshness == Freshness::Stale);
    let title = if !st.snapshot.health_seen {
        Line::from(" services: no supervisor/health yet ")
    } else if health_stale {
        Line::from(vec![
            Span::raw(" services "),
            Span::styled(
                "(supervisor/health STALE: last known) ",
                Style::default().fg(Color::Red).add_modifier(Modifier::BOLD),
            ),
        ])
    } else {
        Line::from(" services (supervisor/health) ")
    };
    let table = Table::new(
        rows,
        [
            Constraint::Length(16),
            Constraint::Length(7),
            Constraint::Length(5),
            Constraint::Length(8),
            Constraint::Length(6),
            Constraint::Length(6),
        ],
    )
    .header(
        Row::new([
            "service", "    pid", "alive", "restarts", "   CPU", "budget",
        ])
        .style(Style::default().add_modifier(Modifier::BOLD | Modifier::UNDERLINED)),
    )
    .block(Block::default().borders(Borders::ALL).title(title));
    Widget::render(table, area, buf);
}

/// Colours of the joints' torque lines.
const JOINT_COLORS: [Color; 7] = [
    Color::Red,
    Color::Green,
    Color::Yellow,
    Color::Blue,
    Color::Magenta,
    Color::Cyan,
    Color::White,
];

fn render_plots(st: &TopState, area: Rect, buf: &mut Buffer) {
    let [a, b, c] = Layout::horizontal([Constraint::Ratio(1, 3); 3]).areas(area);
    let h = &st.history;
    let d: Vec<(f64, f64)> = h.distance.0.iter().copied().collect();
    plot(
        st.t_s,
        " min distance [m] ",
        &[(&d, Color::Cyan)],
        h.distance.bounds(),
        a,
        buf,
    );
    let r: Vec<(f64, f64)> = h.residual.0.iter().copied().collect();
    plot(
        st.t_s,
        " residual ‖r‖ [Nm] ",
        &[(&r, Color::Magenta)],
        h.residual.bounds(),
        b,
        buf,
    );
    let tau: Vec<Vec<(f64, f64)>> = h
        .torque
        .iter()
        .map(|s| s.0.iter().copied().collect())
        .collect();
    let lines: Vec<(&[(f64, f64)], Color)> = tau
        .iter()
        .enumerate()
        .map(|(i, v)| (v.as_slice(), JOINT_COLORS[i % JOINT_COLORS.len()]))
        .collect();
    let bounds = h
        .torque
        .iter()
        .filter_map(Series::bounds)
        .reduce(|x, y| [x[0].min(y[0]), x[1].max(y[1])]);
    plot(st.t_s, " joint torque τ [Nm] ", &lines, bounds, c, buf);
}

/// One chart of the last [`HISTORY_S`] seconds up to `now` \[s\].
fn plot(
    now: f64,
    title: &str,
    lines: &[(&[(f64, f64)], Color)],
    y: Option<[f64; 2]>,
    area: Rect,
    buf: &mut Buffer,
) {
    let [lo, hi] = y.unwrap_or([0.0, 1.0]);
    let pad = ((hi - lo) * 0.05).max(1e-3);
    let (lo, hi) = (lo - pad, hi + pad);
    let datasets = lines
        .iter()
        .map(|(data, color)| {
            Dataset::default()
                .marker(Marker::Braille)
                .graph_type(GraphType::Line)
                .style(Style::default().fg(*color))
                .data(data)
        })
        .collect();
    let dim = Style::default().fg(Color::DarkGray);
    Chart::new(datasets)
        .block(Block::default().borders(Borders::ALL).title(title))
        .x_axis(
            Axis::default()
                .bounds([now - HISTORY_S, now])
                .labels([format!("-{HISTORY_S:.0} s"), "now".into()])
                .style(dim),
        )
        .y_axis(
            Axis::default()
                .bounds([lo, hi])
                .labels([format!("{lo:.2}"), format!("{hi:.2}")])
                .style(dim),
        )
        .render(area, buf);
}

/// The text of a drawn buffer: one line per row, trailing blanks cut.
pub fn buffer_text(buf: &Buffer) -> String {
    let area = buf.area;
    let mut out = String::new();
    for y in area.top()..area.bottom() {
        let mut line = String::new();
        for x in area.left()..area.right() {
            line.push_str(buf[(x, y)].symbol());
        }
        out.push_str(line.trim_end());
        out.push('\n');
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use ratatui::backend::TestBackend;
    use ratatui::Terminal;
    use serde_json::json;

    fn row(
        name: &'static str,
        rate: f64,
        age: Option<f64>,
        mean: Option<f64>,
        drops: u64,
    ) -> ChannelRow {
        let v = json!({"present": true, "publishers": 1, "subscribers": 2, "rate_hz": rate,
                       "mean_interval_ms": mean, "max_interval_ms": mean.map(|m| m * 2.0),
                       "age_ms": age, "bandwidth_bps": rate * 100.0, "total_drops": drops});
        ChannelRow::from_json(name, &v, phri_ipc::ON_DEMAND.contains(&name), None, None)
    }

    fn state() -> TopState {
        let mut st = TopState::new("phri_test_");
        st.t_s = 12.5;
        st.snapshot = Snapshot {
            mode: Some("task"),
            min_distance: Some(0.512),
            residual_norm: Some(1.25),
            residual_flags: residual_flags::VALID,
            collab_phase: Some("idle"),
            contact_force: None,
            braking: false,
            health_seen: true,
        };
        st.channels = vec![
            row("robot/state", 1000.0, Some(0.4), Some(1.0), 0),
            row("control/status", 998.0, Some(0.6), Some(1.002), 3),
            // stopped 5 s ago: stale
            row("camera/depth", 0.0, Some(5000.0), None, 0),
            // exists, never heard: silent
            row("sim/world", 0.0, None, None, 0),
            // on demand, nothing yet: idle
            row("hri/request", 0.0, None, None, 0),
            ChannelRow::from_json("fault/depth", &json!({"present": false}), true, None, None),
        ];
        st.services = vec![
            ServiceRow {
                name: "sim".into(),
                pid: 4242,
                alive: true,
                restarts: 0,
                cpu_share: Some(0.131),
                cpu_budget: Some(0.3),
            },
            ServiceRow {
                name: "camera".into(),
                pid: 4243,
                alive: false,
                restarts: 2,
                cpu_share: None,
                cpu_budget: Some(0.2),
            },
        ];
        // 30 s at 4 Hz up to now
        for k in 0..120 {
            let t = st.t_s - (119 - k) as f64 * 0.25;
            st.history
                .distance
                .push(t, 0.5 + 0.1 * (k as f64 * 0.3).sin());
            st.history.residual.push(t, 1.0 + (k % 5) as f64);
            st.history.torque.resize_with(7, Series::default);
            for (j, s) in st.history.torque.iter_mut().enumerate() {
                s.push(t, j as f64 * 3.0 - 9.0 + (k as f64 * 0.2).cos());
            }
        }
        st
    }

    fn draw(st: &TopState, w: u16, h: u16) -> Buffer {
        let mut term = Terminal::new(TestBackend::new(w, h)).unwrap();
        term.draw(|f| render(st, f.area(), f.buffer_mut())).unwrap();
        term.backend().buffer().clone()
    }

    /// (x, y) of the first cell where `needle` starts on a row.
    fn find(buf: &Buffer, needle: &str) -> Option<(u16, u16)> {
        let text = buffer_text(buf);
        text.lines().enumerate().find_map(|(y, l)| {
            l.find(needle)
                .map(|byte| (l[..byte].chars().count() as u16, y as u16))
        })
    }

    #[test]
    fn the_dashboard_shows_channels_services_mode_and_plots() {
        let buf = draw(&state(), 160, 44);
        let text = buffer_text(&buf);
        for needle in [
            "prefix 'phri_test_'",
            "mode task",
            "min distance 0.512 m",
            "residual ‖r‖ 1.25 Nm",
            "robot/state",
            "1000.0",
            "0.40",
            "control/status",
            "camera/depth",
            "STALE",
            "silent",
            "idle",
            "absent",
            "services (supervisor/health)",
            "sim",
            "4242",
            "NO",
            "13.1%",
            "30.0%",
            "budget",
            "min distance [m]",
            "residual ‖r‖ [Nm]",
            "joint torque τ [Nm]",
            "sort: cell order",
        ] {
            assert!(text.contains(needle), "'{needle}' missing from\n{text}");
        }
        // the plots draw lines (braille dots) inside their boxes
        let (px, py) = find(&buf, "min distance [m]").unwrap();
        let dots = (py..buf.area.height)
            .flat_map(|y| (px..px + 50).map(move |x| (x, y)))
            .filter(|&p| {
                buf[p]
                    .symbol()
                    .chars()
                    .any(|c| ('\u{2801}'..='\u{28ff}').contains(&c))
            })
            .count();
        assert!(
            dots > 20,
            "{dots} braille cells in the distance plot\n{text}"
        );
        let (tx, ty) = find(&buf, "joint torque").unwrap();
        let colours: std::collections::HashSet<Color> = (ty..buf.area.height)
            .flat_map(|y| (tx..buf.area.width).map(move |x| (x, y)))
            .filter(|&p| {
                buf[p]
                    .symbol()
                    .chars()
                    .any(|c| ('\u{2801}'..='\u{28ff}').contains(&c))
            })
            .map(|p| buf[p].fg)
            .collect();
        assert!(colours.len() >= 5, "one colour per joint: {colours:?}");
    }

    #[test]
    fn stale_channels_and_alarms_are_coloured() {
        let buf = draw(&state(), 160, 44);
        let (x, y) = find(&buf, "camera/depth").unwrap();
        assert_eq!(buf[(x, y)].fg, Color::Red, "stale row in red");
        let (x, y) = find(&buf, "sim/world").unwrap();
        assert_eq!(buf[(x, y)].fg, Color::Yellow, "silent row in yellow");
        let (x, y) = find(&buf, "hri/request").unwrap();
        assert_eq!(buf[(x, y)].fg, Color::Reset, "idle on-demand row plain");
        let (x, y) = find(&buf, "robot/state").unwrap();
        assert_eq!(buf[(x, y)].fg, Color::Reset, "fresh row plain");
        // the alarm line: the dead service and the stale channel in red, the restart... none
        let (x, y) = find(&buf, "camera down").unwrap();
        assert_eq!(buf[(x, y)].fg, Color::Red);
        let (x, y) = find(&buf, "stale: camera/depth").unwrap();
        assert_eq!(buf[(x, y)].fg, Color::Red);
        let (x, y) = find(&buf, "silent: sim/world").unwrap();
        assert_eq!(buf[(x, y)].fg, Color::Yellow);
        let (x, y) = find(&buf, "mode task").unwrap();
        assert_eq!(buf[(x + 5, y)].fg, Color::Green);

        let mut st = state();
        st.snapshot.mode = Some("protective_stop");
        st.snapshot.residual_flags |= residual_flags::COLLISION;
        let buf = draw(&st, 160, 44);
        let (x, y) = find(&buf, "mode protective_stop").unwrap();
        assert_eq!(buf[(x + 5, y)].fg, Color::Red);
        assert!(buffer_text(&buf).contains("collision detected"));

        // the supervisor's health stopped: the services are the last known
        st.channels
            .push(row("supervisor/health", 0.0, Some(4000.0), None, 0));
        let buf = draw(&st, 160, 44);
        let (x, y) = find(&buf, "supervisor/health STALE").unwrap();
        assert_eq!(buf[(x, y)].fg, Color::Red);
    }

    #[test]
    fn the_layout_follows_the_terminal_size() {
        let st = state();
        // wide: every column, services beside the channels
        let wide = buffer_text(&draw(&st, 160, 44));
        let l = wide.lines().find(|l| l.contains("robot/state")).unwrap();
        assert!(
            wide.contains("bandwidth") && l.contains("100.0 kB/s"),
            "{wide}"
        );
        let services_row = wide.lines().position(|l| l.contains("services (")).unwrap();
        let channels_row = wide.lines().position(|l| l.contains("channels (")).unwrap();
        assert_eq!(services_row, channels_row, "side by side\n{wide}");
        // 80x24: fewer columns, services below, nothing drawn outside
        let small = draw(&st, 80, 24);
        let text = buffer_text(&small);
        assert_eq!(small.area, Rect::new(0, 0, 80, 24));
        assert!(!text.contains("bandwidth"), "{text}");
        assert!(
            text.contains("robot/state") && text.contains("age ms"),
            "{text}"
        );
        let services_row = text.lines().position(|l| l.contains("services (")).unwrap();
        let channels_row = text.lines().position(|l| l.contains("channels (")).unwrap();
        assert!(services_row > channels_row, "stacked\n{text}");
        // a tiny terminal does not panic
        draw(&st, 20, 5);
    }

    fn key(code: KeyCode) -> KeyEvent {
        KeyEvent::new(code, KeyModifiers::NONE)
    }

    #[test]
    fn keys_sort_select_echo_and_quit() {
        let mut st = state();
        assert_eq!(
            on_key(&mut st, key(KeyCode::Char('s'))),
            KeyOutcome::Continue
        );
        assert_eq!(st.sort, SortBy::Name);
        let names: Vec<_> = st.sorted().iter().map(|r| r.name).collect();
        assert_eq!(names[0], "camera/depth");
        on_key(&mut st, key(KeyCode::Char('s')));
        assert_eq!(st.sort, SortBy::Rate);
        assert_eq!(st.sorted()[0].name, "robot/state");
        on_key(&mut st, key(KeyCode::Char('s')));
        let names: Vec<_> = st.sorted().iter().map(|r| r.name).collect();
        // never heard counts as oldest; absent last
        assert_eq!(
            &names[..3],
            ["sim/world", "hri/request", "camera/depth"],
            "oldest first"
        );
        assert_eq!(names[5], "fault/depth");
        on_key(&mut st, key(KeyCode::Char('s')));
        assert_eq!(st.sorted()[0].name, "control/status", "most drops first");
        on_key(&mut st, key(KeyCode::Char('s')));
        assert_eq!(st.sort, SortBy::Cell);

        // selection moves in the table's order and stops at the ends
        on_key(&mut st, key(KeyCode::Up));
        assert_eq!(st.selected, Some("robot/state"));
        on_key(&mut st, key(KeyCode::Down));
        on_key(&mut st, key(KeyCode::Down));
        assert_eq!(st.selected, Some("camera/depth"));
        for _ in 0..10 {
            on_key(&mut st, key(KeyCode::Down));
        }
        assert_eq!(st.selected, Some("fault/depth"));
        on_key(&mut st, key(KeyCode::Up));
        assert_eq!(st.selected, Some("hri/request"));
        // the selection is drawn
        let text = buffer_text(&draw(&st, 160, 44));
        assert!(text.contains("▶ hri/request"), "{text}");

        // Enter: the echo pane of the selected channel; Esc: back
        on_key(&mut st, key(KeyCode::Up));
        on_key(&mut st, key(KeyCode::Up));
        on_key(&mut st, key(KeyCode::Enter));
        assert_eq!(st.view, View::Echo("camera/depth"));
        st.echo = Some(serde_json::json!({"seq": 7, "width": 640, "min_depth_mm": null}));
        let text = buffer_text(&draw(&st, 160, 44));
        assert!(text.contains("echo camera/depth"), "{text}");
        for l in ["seq=7", "width=640", "min_depth_mm=null"] {
            assert!(text.lines().any(|x| x.contains(l)), "{l}\n{text}");
        }
        assert_eq!(on_key(&mut st, key(KeyCode::Esc)), KeyOutcome::Continue);
        assert_eq!(st.view, View::Channels);
        assert_eq!(st.echo, None);
        assert_eq!(on_key(&mut st, key(KeyCode::Esc)), KeyOutcome::Quit);
        assert_eq!(on_key(&mut st, key(KeyCode::Char('q'))), KeyOutcome::Quit);
        let ctrl_c = KeyEvent::new(KeyCode::Char('c'), KeyModifiers::CONTROL);
        assert_eq!(on_key(&mut st, ctrl_c), KeyOutcome::Quit);
    }

    #[test]
    fn freshness_follows_each_streams_pace() {
        use Freshness::*;
        // 1 kHz: stale after the floor, not after 5 intervals
        assert_eq!(Freshness::of(true, false, Some(10.0), Some(1.0)), Fresh);
        assert_eq!(Freshness::of(true, false, Some(300.0), Some(1.0)), Stale);
        // 10 Hz: 5 intervals
        assert_eq!(Freshness::of(true, false, Some(400.0), Some(100.0)), Fresh);
        assert_eq!(Freshness::of(true, false, Some(600.0), Some(100.0)), Stale);
        // slower than the window: a fixed limit
        assert_eq!(Freshness::of(true, false, Some(900.0), None), Fresh);
        assert_eq!(Freshness::of(true, false, Some(3500.0), None), Stale);
        // never seen; on demand; absent
        assert_eq!(Freshness::of(true, false, None, None), Silent);
        assert_eq!(Freshness::of(true, true, None, None), Idle);
        assert_eq!(Freshness::of(true, true, Some(1e6), None), Fresh);
        assert_eq!(Freshness::of(false, false, None, None), Absent);
        // a 30 Hz stream that stopped 1 s ago, judged by its last known mean interval
        let stopped = json!({"present": true, "age_ms": 1000.0, "mean_interval_ms": null});
        let row = |v: &Value, known, recv| ChannelRow::from_json("x", v, false, known, recv);
        assert_eq!(row(&stopped, Some(33.3), None).freshness, Stale);
        assert_eq!(row(&stopped, None, None).freshness, Fresh);
        // messages without a publish time: judged by when they were received
        let unstamped = json!({"present": true, "age_ms": null, "mean_interval_ms": 1.0});
        let fresh = row(&unstamped, None, Some(2.0));
        assert_eq!((fresh.age_ms, fresh.freshness), (Some(2.0), Fresh));
        assert_eq!(row(&unstamped, None, Some(400.0)).freshness, Stale);
        assert_eq!(row(&unstamped, None, None).freshness, Silent);
    }

    #[test]
    fn series_keep_the_history_span_and_skip_gaps() {
        let mut s = Series::default();
        for k in 0..200 {
            s.push(k as f64 * 0.25, if k == 150 { f64::NAN } else { k as f64 });
        }
        let t_last = 199.0 * 0.25;
        assert!(s
            .0
            .iter()
            .all(|&(t, x)| t >= t_last - HISTORY_S && x.is_finite()));
        assert_eq!(s.0.len(), 120, "30 s at 4 Hz, one gap: {}", s.0.len());
        assert_eq!(s.bounds(), Some([s.0[0].1, 199.0]));
    }

    #[test]
    fn a_process_s_cpu_share_is_its_cpu_time_over_the_wall_clock_smoothed() {
        let mut m = CpuMeter::default();
        assert_eq!(m.share(7, 0.0, 0), None);
        // too soon after the first sample: nothing yet
        assert_eq!(m.share(7, 0.1, 50_000_000), None);
        // 25 % of a core over 0.25 s
        let s = m.share(7, 0.25, 62_500_000).unwrap();
        assert!((s - 0.25).abs() < 1e-9, "{s}");
        // then 125 %: the smoothed share moves 30 % of the way
        let s = m.share(7, 0.5, 375_000_000).unwrap();
        assert!((s - 0.55).abs() < 1e-9, "{s}");
        m.keep_only(&[8]);
        assert_eq!(m.share(7, 0.6, 400_000_000), None);
    }

    #[test]
    fn echo_fields_are_the_echo_line() {
        let v = serde_json::json!({"seq": 3, "q": [0.5, 1.0], "mode": "task"});
        let mut fields = echo_fields(&v);
        fields.sort();
        assert_eq!(fields, vec!["mode=\"task\"", "q=[0.5,1.0]", "seq=3"]);
    }
}
