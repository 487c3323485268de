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

/// The whole screen of `state` in `area`: the roster strip (a fleet), the panels' plan and
/// the context footer's row. [`crate::ui::draw`] draws there and the mouse's hit test reads
/// the same, so a click lands on what is drawn.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Screen {
    pub roster: Option<Rect>,
    pub plan: Plan,
    pub footer: Option<Rect>,
}

pub fn screen(mut area: Rect, fleet: bool) -> Screen {
    let roster = (fleet && area.height > 1).then(|| {
        let strip = Rect { height: 1, ..area };
        area.y += 1;
        area.height -= 1;
        strip
    });
    // The context footer takes the bottom row once the screen has room for panels: from
    // the log where the log is at the bottom (the panels keep their rows), else from all.
    if area.height <= MIN_HEIGHT {
        return Screen {
            roster,
            plan: plan(area),
            footer: None,
        };
    }
    let footer = Rect {
        y: area.bottom() - 1,
        height: 1,
        ..area
    };
    let mut p = plan(area);
    if p.class == SizeClass::Wide {
        p = plan(Rect {
            height: area.height - 1,
            ..area
        });
    } else {
        p.log.height = p.log.height.saturating_sub(1);
    }
    Screen {
        roster,
        plan: p,
        footer: Some(footer),
    }
}

/// The roster strip's room per droid (`mirror`: the MIRROR tag takes its place first).
pub fn roster_room(width: u16, droids: usize, mirror: bool) -> (usize, usize) {
    let tag = if mirror { ROSTER_MIRROR_TAG.len() } else { 0 };
    (tag, (width as usize).saturating_sub(tag) / droids.max(1))
}

/// The roster's mirror tag.
pub const ROSTER_MIRROR_TAG: &str = "MIRROR ";

/// The droid whose roster entry is at column `x` of the strip.
pub fn roster_entry_at(width: u16, droids: usize, mirror: bool, x: u16) -> Option<usize> {
    let (tag, room) = roster_room(width, droids, mirror);
    let x = (x as usize).checked_sub(tag)?;
    let i = x / room.max(1);
    (room > 0 && i < droids).then_some(i)
}

/// The animation or sound palette's box for `names` (display widths) in `area`.
pub fn palette_rect(area: Rect, name_widths: impl Iterator<Item = usize>, len: usize) -> Rect {
    let name_w = name_widths.max().unwrap_or(0).min(48);
    let w = (name_w + 14).max(40) as u16;
    let h = (len as u16).saturating_add(2).max(3);
    centered(
        area,
        w.min(area.width.saturating_sub(2).max(1)),
        h.min(area.height.saturating_sub(2).max(1)),
    )
}

/// First row shown so that `selected` is visible, near the middle when the list scrolls.
pub fn list_offset(selected: usize, len: usize, rows: usize) -> usize {
    if rows == 0 || len <= rows {
        return 0;
    }
    selected
        .min(len - 1)
        .saturating_sub(rows / 2)
        .min(len - rows)
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
