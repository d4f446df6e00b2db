//! The shared look of the pictures: colours, markers, legend marks.

use image::Rgb;

/// Colours that every picture shares, so that plan, simulate and cspace pictures read alike.
pub mod palette {
    use image::Rgb;
    /// Background, and space never seen by the sonar.
    pub const BACKGROUND: Rgb<u8> = Rgb([255, 255, 255]);
    /// Text.
    pub const TEXT: Rgb<u8> = Rgb([20, 20, 20]);
    /// Axes and ticks.
    pub const AXIS: Rgb<u8> = Rgb([70, 70, 80]);
    /// Faint lines at the axis ticks.
    pub const GRID_LINES: Rgb<u8> = Rgb([232, 234, 240]);
    /// The scale bar (a colour no other mark uses, so tests can find it).
    pub const SCALE_BAR: Rgb<u8> = Rgb([30, 30, 110]);
    /// The legend box's border.
    pub const LEGEND_BORDER: Rgb<u8> = Rgb([190, 190, 200]);
    /// Cells occupied in the robot's map (obstacles grown by the planning radius).
    pub const MAP: Rgb<u8> = Rgb([250, 200, 150]);
    /// Obstacles themselves (plan pictures), or a saved map.
    pub const OBSTACLE: Rgb<u8> = Rgb([110, 110, 122]);
    /// Obstacle outlines.
    pub const OUTLINE: Rgb<u8> = Rgb([35, 35, 45]);
    /// Real obstacles the robot does not know (drawn faint).
    pub const REAL: Rgb<u8> = Rgb([150, 150, 160]);
    /// Obstacles known before the start.
    pub const KNOWN: Rgb<u8> = Rgb([35, 35, 45]);
    /// Space the sonar has swept and seen free.
    pub const SEEN: Rgb<u8> = Rgb([214, 236, 250]);
    /// The full plan.
    pub const PLAN: Rgb<u8> = Rgb([110, 150, 255]);
    /// The kept prefix (and `twil plan`'s path).
    pub const PREFIX: Rgb<u8> = Rgb([0, 70, 210]);
    /// The driven trail.
    pub const TRAIL: Rgb<u8> = Rgb([0, 150, 60]);
    /// Sonar hits.
    pub const HITS: Rgb<u8> = Rgb([230, 20, 20]);
    /// The robot.
    pub const ROBOT: Rgb<u8> = Rgb([255, 140, 0]);
    /// Start marker.
    pub const START: Rgb<u8> = Rgb([0, 165, 0]);
    /// Goal marker.
    pub const GOAL: Rgb<u8> = Rgb([200, 0, 200]);
    /// The band the last sweep covered (drawn translucent).
    pub const BAND: Rgb<u8> = Rgb([255, 215, 0]);
    /// The sonar range circle.
    pub const RANGE: Rgb<u8> = Rgb([150, 80, 200]);
    /// A second path to compare with (cspace: the thesis' path).
    pub const COMPARE: Rgb<u8> = Rgb([245, 150, 20]);
    /// cspace: configurations where arm 1 collides.
    pub const ARM1_CELL: Rgb<u8> = Rgb([160, 180, 215]);
    /// cspace: configurations where arm 2 collides.
    pub const ARM2_CELL: Rgb<u8> = Rgb([100, 100, 118]);
    /// cspace: arm 1.
    pub const ARM1: Rgb<u8> = Rgb([60, 120, 200]);
    /// cspace: arm 2 (or the moving object).
    pub const ARM2: Rgb<u8> = Rgb([30, 160, 150]);
    /// cspace: earlier arm positions.
    pub const GHOST: Rgb<u8> = Rgb([205, 205, 215]);
}

/// Opacity of the band wedge over the map.
pub const BAND_ALPHA: f32 = 0.28;
/// Opacity of the unknown real obstacles.
pub const REAL_ALPHA: f32 = 0.45;

/// The colour `color` at opacity `alpha` over white: what a translucent mark looks like on
/// the background, and so its legend swatch.
pub fn over_white(color: Rgb<u8>, alpha: f32) -> Rgb<u8> {
    let a = alpha.clamp(0.0, 1.0);
    Rgb(color
        .0
        .map(|c| (255.0 * (1.0 - a) + c as f32 * a).round() as u8))
}

/// Marker shapes, a fixed size in pixels.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Marker {
    /// A filled disc with a white rim.
    Disc,
    /// A filled diamond with a white rim.
    Diamond,
    /// A filled square with a white rim.
    Square,
}

/// A legend swatch: how the mark looks.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Mark {
    /// A filled square (areas: cells, obstacles, shaded space).
    Fill(Rgb<u8>),
    /// A filled square with an outline (obstacles drawn filled and outlined).
    FillOutline(Rgb<u8>, Rgb<u8>),
    /// A square outline (outlined polygons).
    Outline(Rgb<u8>),
    /// A horizontal line `width` pixels thick (paths).
    Line(Rgb<u8>, f32),
    /// A marker.
    Marker(Marker, Rgb<u8>),
    /// Three dots (sonar hits).
    Dots(Rgb<u8>),
    /// A ring (a circle outline, e.g. the sonar range).
    Ring(Rgb<u8>),
    /// The robot: a translucent disc with outline and heading.
    Robot(Rgb<u8>),
}

impl Mark {
    /// The colour whose exact pixels the swatch shows.
    pub fn color(&self) -> Rgb<u8> {
        match *self {
            Mark::Fill(c)
            | Mark::Outline(c)
            | Mark::Line(c, _)
            | Mark::Marker(_, c)
            | Mark::Dots(c)
            | Mark::Ring(c)
            | Mark::Robot(c) => c,
            Mark::FillOutline(c, _) => c,
        }
    }
}

/// One legend line.
#[derive(Clone, Debug, PartialEq)]
pub struct LegendEntry {
    /// What the mark is.
    pub label: String,
    /// How it looks.
    pub mark: Mark,
}

impl LegendEntry {
    /// An entry.
    pub fn new(label: impl Into<String>, mark: Mark) -> Self {
        Self {
            label: label.into(),
            mark,
        }
    }
}
