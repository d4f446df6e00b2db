//! Pictures of the classic methods: the world, the method's own structure (roadmap, cells,
//! nodes) and its path. `twil plan --planner NAME --png` draws one panel; `twil compare` draws
//! one panel per method with [`draw`].

use image::Rgb;

use super::{min_clearance_m, Method, Run, Status};
use crate::picture::{
    self, palette, Figure, FigureSpec, LegendEntry, Mark, Marker, PanelSpec, Plot,
};
use crate::planning::World;

/// Roadmap and graph edges.
pub const EDGE: Rgb<u8> = Rgb([150, 160, 185]);
/// Outlines of a decomposition's free cells.
pub const CELL: Rgb<u8> = Rgb([120, 185, 140]);
/// Fill of a decomposition's blocked (FULL) cells.
pub const BLOCKED: Rgb<u8> = Rgb([225, 195, 195]);
/// Graph nodes.
pub const NODE: Rgb<u8> = Rgb([90, 90, 120]);

/// The legend entries every classic picture shares, plus those of the overlays `runs` use.
pub fn legend(runs: &[&Run]) -> Vec<LegendEntry> {
    let mut legend = vec![
        LegendEntry::new(
            "obstacle",
            Mark::FillOutline(palette::OBSTACLE, palette::OUTLINE),
        ),
        LegendEntry::new("grown by robot radius", Mark::Fill(palette::MAP)),
    ];
    if runs.iter().any(|r| !r.overlay.blocked_cells.is_empty()) {
        legend.push(LegendEntry::new("blocked cell", Mark::Fill(BLOCKED)));
    }
    if runs.iter().any(|r| !r.overlay.cells.is_empty()) {
        legend.push(LegendEntry::new("free cell", Mark::Line(CELL, 1.5)));
    }
    if runs.iter().any(|r| !r.overlay.edges.is_empty()) {
        legend.push(LegendEntry::new("graph / roadmap", Mark::Line(EDGE, 1.5)));
    }
    // One entry per kind of dot drawn (graph nodes, a local minimum, hit / leave points).
    let mut labels: Vec<&str> = Vec::new();
    for r in runs.iter().filter(|r| !r.overlay.nodes.is_empty()) {
        let label = match r.overlay.node_label {
            "" => "node",
            label => label,
        };
        if !labels.contains(&label) {
            labels.push(label);
            legend.push(LegendEntry::new(label, Mark::Marker(Marker::Disc, NODE)));
        }
    }
    legend.extend([
        LegendEntry::new("path", Mark::Line(palette::PREFIX, 3.0)),
        LegendEntry::new("start", Mark::Marker(Marker::Disc, palette::START)),
        LegendEntry::new("goal", Mark::Marker(Marker::Diamond, palette::GOAL)),
    ]);
    legend
}

/// Draw `world` and `run` on `plot`: grown map, polygons, the method's overlay, path, start and
/// goal.
pub fn draw(plot: &mut Plot<'_>, world: &World, run: &Run) {
    plot.fill_grid(&world.grid, palette::MAP, 1.0);
    for cell in &run.overlay.blocked_cells {
        plot.fill_polygon(&picture::points(cell), BLOCKED, 1.0);
    }
    let ends = [world.params.start, world.params.goal];
    for polygon in world.obstacles.iter() {
        let pts = picture::points(polygon);
        if !picture::encloses(polygon, &ends) {
            plot.fill_polygon(&pts, palette::OBSTACLE, 1.0);
        }
        plot.stroke_polygon(&pts, palette::OUTLINE, 1.0);
    }
    for cell in &run.overlay.cells {
        plot.stroke_polygon(&picture::points(cell), CELL, 1.0);
    }
    for edge in &run.overlay.edges {
        plot.polyline(&picture::points(edge), EDGE, 1.0);
    }
    let path = picture::points(&run.path);
    plot.polyline(&path, palette::PREFIX, 3.0);
    // Over the path, and wider than it: the hit and leave points of Bug and the potential
    // field's minimum lie on the path and were hidden under it.
    plot.dots(&picture::points(&run.overlay.nodes), 3.5, NODE);
    let p = &world.params;
    plot.marker(p.start.x_m, p.start.y_m, Marker::Disc, 14.0, palette::START);
    plot.marker(p.goal.x_m, p.goal.y_m, Marker::Diamond, 16.0, palette::GOAL);
}

/// One line saying how `run` ended: status, length, clearance.
pub fn result_line(world: &World, run: &Run) -> String {
    let mut s = format!(
        "{}: {}",
        run.method.as_str(),
        run.status.as_str().replace('_', " ")
    );
    if run.status == Status::Found {
        s.push_str(&format!(", {:.2} m", run.length_m));
    }
    if let Some(c) = min_clearance_m(world, run) {
        let c = format!("{c:.2}").replace("-0.00", "0.00");
        s.push_str(&format!(", clearance {c} m"));
    }
    s
}

/// The name of `world`'s `.da` file, for captions.
pub fn world_name(world: &World) -> String {
    world
        .world_path
        .as_ref()
        .and_then(|p| p.file_name())
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_else(|| "(no world)".into())
}

/// The picture of one method's run (`twil plan --planner NAME --png`).
pub fn figure(world: &World, run: &Run, px_per_cell: Option<u32>) -> anyhow::Result<Figure> {
    let g = *world.grid.geometry();
    let scale = px_per_cell.unwrap_or_else(|| picture::fit_px_per_cell(g, 800));
    let caption = vec![
        format!(
            "{} · twil plan --planner {} · {}",
            world_name(world),
            run.method.as_str(),
            result_line(world, run)
        ),
        format!(
            "{}; {} {} in {} us, {} bytes; robot radius {:.2} m.",
            why(run.method),
            run.expanded,
            run.expanded_unit,
            run.elapsed_us,
            run.memory_bytes,
            world.params.robot_radius_m
        ),
    ];
    let mut fig = Figure::new(&FigureSpec {
        caption,
        caption_lines: None,
        panels: vec![PanelSpec::map(g, scale, None)],
        panels_per_row: None,
        legend: legend(&[run]),
    })
    .map_err(|e| anyhow::anyhow!("--scale {scale}: the picture: {e}"))?;
    let mut plot = fig
        .plot(0)
        .ok_or_else(|| anyhow::anyhow!("picture: no plot"))?;
    draw(&mut plot, world, run);
    Ok(fig)
}

/// What the method does, in a few words (for captions).
pub fn why(method: Method) -> &'static str {
    match method {
        Method::Bfs => "Fewest 8-connected steps on the grid of grown obstacles",
        Method::Astar => "Shortest 8-connected path on the grid of grown obstacles",
        Method::Anyangle => "Straight segments with line of sight on the grid",
        Method::Visgraph => {
            "Shortest path along the visibility graph of the grown obstacles' corners"
        }
        Method::Voronoi => "The ridges of the free space, farthest from every obstacle",
        Method::Trapezoid => {
            "Vertical trapezoids by a sweep line, through midpoints of shared edges"
        }
        Method::Quadtree => {
            "Square leaves split where mixed, until the empty ones join start and goal"
        }

        Method::Potential => "Descent on an attractive paraboloid plus repulsion from obstacles",
        Method::Bug => "Drive at the goal, follow an obstacle's edge when the sonar blocks the way",
    }
}
