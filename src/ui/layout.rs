//! Where each panel goes, chosen per terminal size. Plain arithmetic rather than the
//! constraint solver: the split is predictable, cheap, and never hands out a rect outside the
//! frame. Panels adapt their content to the rect they get (e.g. sensors drop the gyro line when
//! short), so this module only decides sizes.

use ratatui::layout::Rect;

/// Below this the panels cannot be drawn legibly; only the status bar and the log remain.
pub const MIN_WIDTH: u16 = 60;
pub const MIN_HEIGHT: u16 = 16;
/// From this size on everything is side by side with a tall packet log.
const WIDE_WIDTH: u16 = 150;
const WIDE_HEIGHT: u16 = 40;
/// Compact layouts this wide have room for the map.
const COMPACT_MAP_WIDTH: u16 = 110;
pub const STATUS_ROWS: u16 = 2;

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum SizeClass {
    /// Too small for panels: status bar, a notice and the log.
    Tiny,
    /// Panels stacked above the log, map only when wide enough (80×24 lives here).
    Compact,
    /// Panels on the left, a full-height packet log on the right.
    Wide,
}

impl SizeClass {
    pub fn of(area: Rect) -> SizeClass {
        if area.width >= WIDE_WIDTH && area.height >= WIDE_HEIGHT {
            SizeClass::Wide
        } else if area.width >= MIN_WIDTH && area.height >= MIN_HEIGHT {
            SizeClass::Compact
        } else {
            SizeClass::Tiny
        }
    }
}

/// The rects of one frame. Panels that do not fit this size are `None`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Plan {
    pub class: SizeClass,
    pub status: Rect,
    pub drive: Option<Rect>,
    pub dome: Option<Rect>,
    pub sensors: Option<Rect>,
    pub collisions: Option<Rect>,
    pub map: Option<Rect>,
    pub log: Rect,
    /// Tiny only: one row asking for a bigger terminal.
    pub notice: Option<Rect>,
}

/// Split `h` rows off the top (clamped to what is there).
fn top(area: Rect, h: u16) -> (Rect, Rect) {
    let h = h.min(area.height);
    (
        Rect { height: h, ..area },
        Rect {
            y: area.y + h,
            height: area.height - h,
            ..area
        },
    )
}

/// Split `w` columns off the left (clamped to what is there).
fn left(area: Rect, w: u16) -> (Rect, Rect) {
    let w = w.min(area.width);
    (
        Rect { width: w, ..area },
        Rect {
            x: area.x + w,
            width: area.width - w,
            ..area
        },
    )
}

/// Split `h` rows off the bottom.
fn bottom(area: Rect, h: u16) -> (Rect, Rect) {
    let (rest, b) = top(area, area.height.saturating_sub(h));
    (rest, b)
}

pub fn plan(area: Rect) -> Plan {
    let class = SizeClass::of(area);
    let (status, body) = top(area, STATUS_ROWS);
    let empty = Plan {
        class,
        status,
        drive: None,
        dome: None,
        sensors: None,
        collisions: None,
        map: None,
        log: body,
        notice: None,
    };
    match class {
        SizeClass::Tiny => {
            let (notice, log) = top(body, 1);
            Plan {
                notice: Some(notice),
                log,
                ..empty
            }
        }
        SizeClass::Compact => compact(body, empty),
        SizeClass::Wide => wide(body, empty),
    }
}

/// Panels on top, the log below. The top grows with the height (so tall terminals get the gyro
/// and a bigger dial) but always leaves the log a few lines.
fn compact(body: Rect, p: Plan) -> Plan {
    let top_h = body
        .height
        .saturating_sub(10)
        .clamp(11, (body.height / 2).max(12))
        .min(body.height.saturating_sub(3));
    let (panels, log) = top(body, top_h);
    let (drive, rest) = left(panels, panels.width * 45 / 100);
    let (drive, map, right) = if panels.width >= COMPACT_MAP_WIDTH {
        let (drive, rest) = left(panels, panels.width * 30 / 100);
        let (map, right) = left(rest, panels.width * 30 / 100);
        (drive, Some(map), right)
    } else {
        (drive, None, rest)
    };
    let dome_h = if top_h >= 16 { 5 } else { 3 };
    let (dome, rest) = top(right, dome_h);
    let coll_h = if top_h >= 12 { 4 } else { 3 };
    let (sensors, collisions) = bottom(rest, coll_h);
    Plan {
        drive: Some(drive),
        dome: Some(dome),
        sensors: Some(sensors),
        collisions: Some(collisions),
        map,
        log,
        ..p
    }
}

/// Left half: dial and map on top, dome, then sensors beside collisions. Right: the log.
fn wide(body: Rect, p: Plan) -> Plan {
    let (panels, log) = left(body, (body.width / 2).clamp(76, 110));
    let (rest, lower) = bottom(panels, 12);
    let (sensors, collisions) = left(lower, lower.width * 55 / 100);
    let (upper, dome) = bottom(rest, 5);
    let (drive, map) = left(upper, upper.width / 2);
    Plan {
        drive: Some(drive),
        dome: Some(dome),
        sensors: Some(sensors),
        collisions: Some(collisions),
        map: Some(map),
        log,
        ..p
    }
}

/// A rect of at most `w`×`h` centred in `area` (overlays).
pub fn centered(area: Rect, w: u16, h: u16) -> Rect {
    let w = w.min(area.width);
    let h = h.min(area.height);
    Rect {
        x: area.x + (area.width - w) / 2,
        y: area.y + (area.height - h) / 2,
        width: w,
        height: h,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn inside(outer: Rect, r: Rect) -> bool {
        r.x >= outer.x
            && r.y >= outer.y
            && r.right() <= outer.right()
            && r.bottom() <= outer.bottom()
    }

    #[test]
    fn every_rect_is_inside_the_frame() {
        for (w, h) in [
            (0, 0),
            (1, 1),
            (20, 5),
            (59, 30),
            (60, 16),
            (80, 24),
            (120, 36),
            (160, 48),
            (300, 100),
        ] {
            let area = Rect::new(0, 0, w, h);
            let p = plan(area);
            for r in [
                Some(p.status),
                p.drive,
                p.dome,
                p.sensors,
                p.collisions,
                p.map,
                Some(p.log),
                p.notice,
            ]
            .into_iter()
            .flatten()
            {
                assert!(inside(area, r), "{w}x{h}: {r:?}");
            }
        }
    }

    #[test]
    fn classes() {
        assert_eq!(plan(Rect::new(0, 0, 80, 24)).class, SizeClass::Compact);
        assert_eq!(plan(Rect::new(0, 0, 160, 48)).class, SizeClass::Wide);
        assert_eq!(plan(Rect::new(0, 0, 40, 24)).class, SizeClass::Tiny);
        assert!(plan(Rect::new(0, 0, 80, 24)).map.is_none());
        assert!(plan(Rect::new(0, 0, 120, 30)).map.is_some());
    }
}
