use super::*;

fn spec(px_per_cell: u32) -> FigureSpec {
    let g = GridGeometry::new(100, 60, 0.05).unwrap(); // 5 m x 3 m
    FigureSpec {
        caption: vec!["a caption".into()],
        caption_lines: None,
        panels: vec![PanelSpec::map(g, px_per_cell, Some("title".into()))],
        panels_per_row: None,
        legend: vec![
            LegendEntry::new("area", Mark::Fill(palette::MAP)),
            LegendEntry::new("path", Mark::Line(palette::PREFIX, 3.0)),
            LegendEntry::new("start", Mark::Marker(Marker::Disc, palette::START)),
            LegendEntry::new("hits", Mark::Dots(palette::HITS)),
            LegendEntry::new("range", Mark::Ring(palette::RANGE)),
            LegendEntry::new("robot", Mark::Robot(palette::ROBOT)),
            LegendEntry::new("known", Mark::Outline(palette::KNOWN)),
        ],
    }
}

fn count_in(img: &RgbImage, r: PxRect, c: Rgb<u8>) -> usize {
    (r.y0..r.y1)
        .flat_map(|y| (r.x0..r.x1).map(move |x| (x, y)))
        .filter(|&(x, y)| img.get_pixel(x as u32, y as u32) == &c)
        .count()
}

#[test]
fn scale_bar_is_one_metre_long_at_the_picture_scale() {
    for (px_per_cell, metres) in [(2, 1.0), (4, 1.0), (1, 2.0)] {
        let fig = Figure::new(&spec(px_per_cell)).unwrap();
        let bar = fig.scale_bar(0).unwrap();
        assert_eq!(bar.length, metres);
        let px_per_m = px_per_cell as f32 / 0.05;
        let img = fig.to_image();
        // Measure the run of bar-coloured pixels along the bar's middle row.
        let y = ((bar.rect.y0 + bar.rect.y1) / 2) as u32;
        let run: Vec<u32> = (0..img.width())
            .filter(|&x| img.get_pixel(x, y) == &palette::SCALE_BAR)
            .collect();
        assert_eq!(
            run.len() as f32,
            (metres * px_per_m).round(),
            "{px_per_cell}"
        );
        assert_eq!(run.first().copied(), Some(bar.rect.x0 as u32));
        // Contiguous, and under the plot, left-aligned with it.
        assert_eq!(run.last().unwrap() - run[0] + 1, run.len() as u32);
        let plot = fig.plot_rect(0).unwrap();
        assert_eq!(bar.rect.x0, plot.x0);
        assert!(bar.rect.y0 > plot.y1);
        // Nothing else in the picture has the bar's colour.
        let total = img.pixels().filter(|p| **p == palette::SCALE_BAR).count();
        assert_eq!(
            total as i32,
            (bar.rect.x1 - bar.rect.x0) * SCALE_BAR_THICKNESS_PX
        );
    }
}

#[test]
fn every_legend_swatch_shows_its_colour_inside_the_legend_box() {
    let s = spec(2);
    let fig = Figure::new(&s).unwrap();
    let img = fig.to_image();
    let lb = fig.legend_box();
    assert_eq!(fig.legend_swatches().len(), s.legend.len());
    for (entry, sw) in s.legend.iter().zip(fig.legend_swatches()) {
        assert!(lb.contains(sw.x0, sw.y0) && lb.contains(sw.x1 - 1, sw.y1 - 1));
        let grown = PxRect {
            x0: sw.x0 - 3,
            y0: sw.y0 - 3,
            x1: sw.x1 + 3,
            y1: sw.y1 + 3,
        };
        assert!(
            count_in(&img, grown, entry.mark.color()) >= 3,
            "{} swatch colour missing",
            entry.label
        );
    }
    // The legend fits: its box lies within the picture, every label ends inside it (none is
    // cut, as the old GIF's "ROBO" was), and there is text right of each swatch.
    assert!(lb.x1 <= img.width() as i32 && lb.y1 <= img.height() as i32);
    for (entry, sw) in s.legend.iter().zip(fig.legend_swatches()) {
        let end = sw.x1 as f32 + 6.0 + text::width_px(&entry.label, LABEL_PX);
        assert!(
            end < lb.x1 as f32,
            "{} ends at {end}, box at {}",
            entry.label,
            lb.x1
        );
    }
    for sw in fig.legend_swatches() {
        let label = PxRect {
            x0: sw.x1 + 4,
            y0: sw.y0,
            x1: (sw.x1 + 30).min(img.width() as i32),
            y1: sw.y1,
        };
        let dark = (label.y0..label.y1)
            .flat_map(|y| (label.x0..label.x1).map(move |x| (x, y)))
            .filter(|&(x, y)| img.get_pixel(x as u32, y as u32).0[0] < 100)
            .count();
        assert!(dark > 5, "no label text right of the swatch at {sw:?}");
    }
}

#[test]
fn data_points_map_with_y_up_and_are_clipped_to_the_plot() {
    let mut fig = Figure::new(&spec(2)).unwrap();
    let plot = fig.plot_rect(0).unwrap();
    {
        let mut p = fig.plot(0).unwrap();
        assert_eq!(p.to_px(0.0, 0.0), (plot.x0 as f32, plot.y1 as f32));
        assert_eq!(p.to_px(5.0, 3.0), (plot.x1 as f32, plot.y0 as f32));
        p.fill_box(0.0, 0.0, 0.05, 0.05, palette::HITS, 1.0);
        // Far beyond the map: clipped away.
        p.fill_box(-10.0, -10.0, 20.0, -1.0, palette::GOAL, 1.0);
        p.polyline(&[(-5.0, 1.0), (10.0, 1.0)], palette::TRAIL, 3.0);
    }
    let img = fig.to_image();
    assert_eq!(
        img.get_pixel(plot.x0 as u32, plot.y1 as u32 - 1),
        &palette::HITS
    );
    assert_eq!(count_in(&img, plot, palette::HITS), 4);
    assert_eq!(img.pixels().filter(|p| **p == palette::GOAL).count(), 0);
    let trail: Vec<(u32, u32)> = img
        .enumerate_pixels()
        .filter(|(_, _, p)| **p == palette::TRAIL)
        .map(|(x, y, _)| (x, y))
        .collect();
    assert!(!trail.is_empty());
    assert!(trail
        .iter()
        .all(|&(x, y)| plot.contains(x as i32, y as i32)));
}

#[test]
fn ticks_are_labelled_in_round_steps() {
    let a = Axis {
        min: 0.0,
        max: 15.0,
        px_per_unit: 40.0,
        title: "x (m)".into(),
    };
    let (step, t) = ticks(&a, 60.0);
    assert_eq!(step, 2.0);
    assert_eq!(t.first().unwrap().0, 0.0);
    assert_eq!(t.last().unwrap().0, 14.0);
    assert_eq!(tick_label(0.5, 0.5), "0.5");
    assert_eq!(tick_label(-0.0, 1.0), "0");
    assert_eq!(tick_label(-180.0, 60.0), "-180");
    assert_eq!(scale_bar_length(40.0), 1.0);
    assert_eq!(scale_bar_length(20.0), 2.0);
    assert_eq!(scale_bar_length(1.5), 50.0);
}

#[test]
fn absurd_input_is_refused_or_draws_nothing() {
    let mut s = spec(2);
    s.panels[0].x.px_per_unit = f32::NAN;
    assert!(Figure::new(&s).is_err());
    let mut s = spec(2);
    s.panels[0].x.max = 1.0e9;
    assert!(Figure::new(&s).is_err());
    let mut fig = Figure::new(&spec(2)).unwrap();
    let before = fig.to_image();
    {
        let mut p = fig.plot(0).unwrap();
        let far = (1.0e30, -1.0e30);
        let nan = (f32::NAN, 1.0);
        p.polyline(&[far, nan, far], palette::PLAN, 5.0);
        p.fill_polygon(&[far, nan, far], palette::PLAN, 1.0);
        p.disc(1.0e30, 0.0, 1.0e30, palette::PLAN, 1.0);
        p.wedge(nan, 1.0, f32::INFINITY, 1.0, palette::PLAN, 0.5);
        p.robot(f32::NAN, 0.0, 0.2, 0.0, palette::PLAN);
        p.marker(f32::INFINITY, 0.0, Marker::Diamond, 1.0e9, palette::PLAN);
        p.fill_box(f32::NAN, 0.0, 1.0, 1.0, palette::PLAN, 1.0);
    }
    assert!(fig.plot(1).is_none());
    assert_eq!(fig.to_image(), before);
}

#[test]
fn a_caption_too_long_for_one_line_wraps_instead_of_being_cut() {
    let mut s = spec(1);
    let long = "word ".repeat(60);
    s.caption = vec![long.trim().to_string()];
    let one = Figure::new(&spec(1)).unwrap().size_px();
    let fig = Figure::new(&s).unwrap();
    assert!(fig.size_px().1 > one.1 + 2 * CAPTION_PX as u32);
    assert_eq!(fig.size_px().0, one.0);
}

#[test]
fn a_room_around_the_start_is_drawn_as_an_outline_and_an_obstacle_is_filled() {
    use twil_core::geom::PointM;
    let room = [
        PointM::new(0.0, 0.0),
        PointM::new(4.0, 0.0),
        PointM::new(4.0, 3.0),
        PointM::new(0.0, 3.0),
    ];
    let start = PointM::new(1.0, 1.0);
    let outside = PointM::new(5.0, 1.0);
    assert!(super::encloses(&room, &[outside, start]));
    assert!(!super::encloses(&room, &[outside]));
    // A wall (2 vertices) encloses nothing.
    assert!(!super::encloses(&room[..2], &[start]));
}
