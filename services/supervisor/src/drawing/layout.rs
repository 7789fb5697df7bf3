//! Where the picture puts each box and how each arrow runs, by hand: the
//! default cell's processes left to right in the order data flows (the
//! robot and the sensors, perception, the residual, the controllers; the
//! observers below), the torque loop's arrows over the top. Coordinates
//! are SVG user units (px at 100 %), y down. A service no place names, or
//! an arrow no route names, is still drawn (a spare place at the bottom, a
//! straight arrow); the tests of [`super`] fail on either for the default
//! cell, so that a change of the cell is a change of this file too.

/// An axis-aligned rectangle \[px\].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Rect {
    /// left edge
    pub x: f64,
    /// top edge (y down)
    pub y: f64,
    /// width
    pub w: f64,
    /// height
    pub h: f64,
}

impl Rect {
    /// A rectangle of size `w` × `h` whose top-left corner is (`x`, `y`).
    pub const fn new(x: f64, y: f64, w: f64, h: f64) -> Rect {
        Rect { x, y, w, h }
    }

    /// A rectangle of size `w` × `h` centred on (`cx`, `cy`).
    pub fn centred(cx: f64, cy: f64, w: f64, h: f64) -> Rect {
        Rect::new(cx - w / 2.0, cy - h / 2.0, w, h)
    }

    /// Its right edge: `x + w`.
    pub fn right(&self) -> f64 {
        self.x + self.w
    }

    /// Its bottom edge: `y + h` (y down).
    pub fn bottom(&self) -> f64 {
        self.y + self.h
    }

    /// The interiors overlap (touching edges do not).
    pub fn overlaps(&self, o: &Rect) -> bool {
        self.x < o.right() && o.x < self.right() && self.y < o.bottom() && o.y < self.bottom()
    }

    /// The segment `a`–`b` (horizontal or vertical, or any) passes through
    /// the interior, shrunk by `margin`.
    pub fn crossed_by(&self, a: (f64, f64), b: (f64, f64), margin: f64) -> bool {
        let inner = Rect::new(
            self.x + margin,
            self.y + margin,
            self.w - 2.0 * margin,
            self.h - 2.0 * margin,
        );
        // sample the segment: fine enough for boxes tens of px wide
        let n = ((b.0 - a.0).abs() + (b.1 - a.1).abs()).ceil().max(1.0) as usize;
        (0..=n).any(|k| {
            let t = k as f64 / n as f64;
            let (x, y) = (a.0 + t * (b.0 - a.0), a.1 + t * (b.1 - a.1));
            x > inner.x && x < inner.right() && y > inner.y && y < inner.bottom()
        })
    }

    /// The point lies on the border (within 0.5 px).
    pub fn on_border(&self, p: (f64, f64)) -> bool {
        let within = |v: f64, lo: f64, hi: f64| v >= lo - 0.5 && v <= hi + 0.5;
        let near = |v: f64, e: f64| (v - e).abs() <= 0.5;
        (within(p.0, self.x, self.right()) && (near(p.1, self.y) || near(p.1, self.bottom())))
            || (within(p.1, self.y, self.bottom())
                && (near(p.0, self.x) || near(p.0, self.right())))
    }
}

/// One box of the picture.
#[derive(Clone, Debug, PartialEq)]
pub struct Place {
    /// its name in [`ROUTES`]
    pub slot: &'static str,
    /// the roster's services it holds (one box for the hot standby pair,
    /// one for the repulsion workers)
    pub services: &'static [&'static str],
    /// where \[px\]
    pub rect: Rect,
    /// what its processes do, in a few words
    pub what: &'static str,
    /// it reads for the record, not for the cell: its reads are listed in
    /// its box, not drawn as arrows (the supervisor, the ROS 2 bridge)
    pub observer: bool,
}

const fn place(
    slot: &'static str,
    services: &'static [&'static str],
    rect: Rect,
    what: &'static str,
) -> Place {
    Place {
        slot,
        services,
        rect,
        what,
        observer: false,
    }
}

/// The supervisor's name among the places' services.
pub const SUPERVISOR: &str = "(supervisor)";

/// The picture's size \[px\].
pub const WIDTH: f64 = 1110.0;
/// The picture's height \[px\].
pub const HEIGHT: f64 = 700.0;

// columns: sources, perception, repulsion, control
const C0: f64 = 40.0;
const C1: f64 = 360.0;
const C2: f64 = 630.0;
const C3: f64 = 920.0;

/// Every box, where it goes.
pub const PLACES: &[Place] = &[
    place(
        "sim",
        &["sim"],
        Rect::new(C0, 76.0, 150.0, 60.0),
        "the arm, the person",
    ),
    place(
        "dynamics",
        &["dynamics", "dynamics_standby"],
        Rect::new(C1, 76.0, 150.0, 60.0),
        "momentum residual",
    ),
    place(
        "camera",
        &["camera"],
        Rect::new(C0, 196.0, 150.0, 76.0),
        "depth frames, 30 Hz",
    ),
    place(
        "perception",
        &["perception"],
        Rect::new(C1, 196.0, 150.0, 76.0),
        "depth ingestion",
    ),
    place(
        "repulsion",
        &["repulsion0", "repulsion1", "repulsion2", "repulsion3"],
        Rect::new(C2, 204.0, 144.0, 60.0),
        "control points",
    ),
    place(
        "gesture",
        &["gesture"],
        Rect::new(C1, 312.0, 150.0, 50.0),
        "the wave",
    ),
    place(
        "mic",
        &["mic"],
        Rect::new(C0, 412.0, 150.0, 64.0),
        "microphone",
    ),
    place(
        "voice",
        &["voice"],
        Rect::new(C1, 412.0, 150.0, 64.0),
        "voice commands",
    ),
    place(
        "control",
        &["control", "control_standby"],
        Rect::new(C3, 76.0, 170.0, 400.0),
        "torque control,\nin charge + hot standby",
    ),
    Place {
        observer: true,
        ..place(
            "supervisor",
            &[SUPERVISOR],
            Rect::new(C0, 520.0, 580.0, 124.0),
            "starts, watches, restarts and stops every process; writes the run report",
        )
    },
    Place {
        observer: true,
        ..place(
            "ros2",
            &["ros2"],
            Rect::new(640.0, 520.0, 240.0, 124.0),
            "the ROS 2 bridge",
        )
    },
];

/// Where a service that no place names goes: the `k`-th spare place, in a
/// row below the others.
pub fn spare_place(k: usize, service: &str) -> Place {
    let _ = service;
    Place {
        slot: "",
        services: &[],
        rect: Rect::new(C0 + k as f64 * 170.0, HEIGHT + 20.0, 150.0, 60.0),
        what: "(no place in drawing/layout.rs)",
        observer: false,
    }
}

/// Where an arrow's label goes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Label {
    /// on segment `i` of the route, upright
    On(usize),
    /// on segment `i`, turned to run up a vertical segment
    Turned(usize),
    /// none: the route starts along another route with the same channels,
    /// whose label names them
    Shared,
}

/// The course of one arrow, from the publisher's box to the reader's.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Route {
    /// the publisher's place (its `slot`)
    pub from: &'static str,
    /// the reader's place (its `slot`)
    pub to: &'static str,
    /// the polyline \[px\], the first point on `from`'s border, the last on `to`'s
    pub points: &'static [(f64, f64)],
    /// where its label goes
    pub label: Label,
}

const fn route(
    from: &'static str,
    to: &'static str,
    points: &'static [(f64, f64)],
    label: Label,
) -> Route {
    Route {
        from,
        to,
        points,
        label,
    }
}

/// Every arrow of the default cell, how it runs.
pub const ROUTES: &[Route] = &[
    // the torque loop, over the top
    route(
        "sim",
        "control",
        &[(170.0, 76.0), (170.0, 52.0), (960.0, 52.0), (960.0, 76.0)],
        Label::On(1),
    ),
    route(
        "control",
        "sim",
        &[(1050.0, 76.0), (1050.0, 22.0), (70.0, 22.0), (70.0, 76.0)],
        Label::On(1),
    ),
    route(
        "sim",
        "dynamics",
        &[(190.0, 106.0), (360.0, 106.0)],
        Label::On(0),
    ),
    route(
        "dynamics",
        "control",
        &[(510.0, 106.0), (920.0, 106.0)],
        Label::On(0),
    ),
    // the call for the standby's residual, back under it
    route(
        "control",
        "dynamics",
        &[(920.0, 128.0), (510.0, 128.0)],
        Label::On(0),
    ),
    route(
        "sim",
        "perception",
        &[
            (190.0, 126.0),
            (300.0, 126.0),
            (300.0, 212.0),
            (360.0, 212.0),
        ],
        Label::On(1),
    ),
    route(
        "sim",
        "camera",
        &[(115.0, 136.0), (115.0, 196.0)],
        Label::On(0),
    ),
    route(
        "sim",
        "mic",
        &[(40.0, 120.0), (20.0, 120.0), (20.0, 444.0), (40.0, 444.0)],
        Label::Turned(1),
    ),
    // perception
    route(
        "camera",
        "perception",
        &[(190.0, 244.0), (360.0, 244.0)],
        Label::On(0),
    ),
    route(
        "camera",
        "gesture",
        &[
            (190.0, 264.0),
            (262.0, 264.0),
            (262.0, 337.0),
            (360.0, 337.0),
        ],
        Label::On(1),
    ),
    route(
        "camera",
        "voice",
        &[
            (190.0, 264.0),
            (262.0, 264.0),
            (262.0, 430.0),
            (360.0, 430.0),
        ],
        Label::Shared,
    ),
    route(
        "camera",
        "control",
        &[
            (190.0, 264.0),
            (262.0, 264.0),
            (262.0, 387.0),
            (920.0, 387.0),
        ],
        Label::On(2),
    ),
    route(
        "perception",
        "repulsion",
        &[(510.0, 234.0), (630.0, 234.0)],
        Label::On(0),
    ),
    route(
        "perception",
        "control",
        &[(490.0, 272.0), (490.0, 290.0), (920.0, 290.0)],
        Label::On(1),
    ),
    route(
        "repulsion",
        "control",
        &[(774.0, 234.0), (920.0, 234.0)],
        Label::On(0),
    ),
    route(
        "control",
        "perception",
        &[(920.0, 160.0), (450.0, 160.0), (450.0, 196.0)],
        Label::On(0),
    ),
    // people
    route(
        "mic",
        "voice",
        &[(190.0, 460.0), (360.0, 460.0)],
        Label::On(0),
    ),
    route(
        "gesture",
        "control",
        &[(510.0, 337.0), (920.0, 337.0)],
        Label::On(0),
    ),
    route(
        "voice",
        "control",
        &[(510.0, 444.0), (920.0, 444.0)],
        Label::On(0),
    ),
    route(
        "ros2",
        "control",
        &[(880.0, 560.0), (985.0, 560.0), (985.0, 476.0)],
        Label::On(0),
    ),
];

/// The route of the arrow `from` → `to`, if the layout has one.
pub fn route_of(from: &str, to: &str) -> Option<&'static Route> {
    ROUTES.iter().find(|r| r.from == from && r.to == to)
}
