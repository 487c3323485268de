//! One room shared by several simulated droids: they see the same walls (the room is centred
//! on (0, 0); each droid starts at its own place in it, which is its locator's (0, 0)) and
//! they collide with each other. Both report such a collision: the droid that ran into the
//! other stops as at a wall and reports at once; the one struck reports it at its next
//! physics step (at the latest its next sensor sample while it streams: its host sleeps until
//! then when it has nothing to say).
//!
//! Each body steps on its own clock (its host's pump); the room holds where each was at its
//! last step. Under paused tokio time the pumps wake in a fixed order, so a fleet mission in
//! the simulator gives the same results every run.

use std::sync::{Arc, Mutex};

/// Droids start this far apart along the x axis.
pub const SPACING_CM: f32 = 60.0;

/// A fleet's droids start at least this far from the walls (centre to wall).
pub const EDGE_CM: f32 = 40.0;

#[derive(Debug, Clone)]
pub(super) struct Occupant {
    pub(super) x: f32,
    pub(super) y: f32,
    pub(super) radius: f32,
    /// A hit by another droid not yet reported.
    hit: Option<Hit>,
    /// What it shows the others in infrared (BOLT, RVR; [`super::infrared`]).
    pub(super) ir: super::infrared::Station,
}

/// A hit taken from another droid: the direction it came from (a unit vector from this
/// droid toward the one that hit it) and how fast that one came, cm/s.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Hit {
    pub dx: f32,
    pub dy: f32,
    pub speed: f32,
}

/// A droid that ran into another: where it stops (touching it) and the direction of the
/// other, as a unit vector.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Contact {
    pub x: f32,
    pub y: f32,
    pub nx: f32,
    pub ny: f32,
}

/// The room several bodies share. Cloning shares it.
#[derive(Debug, Clone, Default)]
pub struct SharedRoom(Arc<Mutex<Vec<Occupant>>>);

/// One droid's place in a [`SharedRoom`].
#[derive(Debug, Clone)]
pub struct Place {
    pub(super) room: SharedRoom,
    pub(super) id: usize,
    /// Where the droid starts, in room coordinates (its locator's origin).
    pub origin: (f32, f32),
}

impl SharedRoom {
    pub fn new() -> SharedRoom {
        SharedRoom::default()
    }

    pub(super) fn lock(&self) -> std::sync::MutexGuard<'_, Vec<Occupant>> {
        crate::sync::lock(&self.0)
    }

    /// A place for one more droid of `radius`, starting at `origin`.
    pub fn place(&self, origin: (f32, f32), radius: f32) -> Place {
        let mut all = self.lock();
        all.push(Occupant {
            x: origin.0,
            y: origin.1,
            radius,
            hit: None,
            ir: Default::default(),
        });
        Place {
            room: self.clone(),
            id: all.len() - 1,
            origin,
        }
    }

    /// Where the `n` droids of a fleet start, inside the room (issue 27 point 9: 16 droids in
    /// a row 60 cm apart sat at ±450 cm, the walls at ±190): in a row along x, centred,
    /// [`SPACING_CM`] apart, while the row fits; else in a centred grid of rows as square as
    /// can be, [`SPACING_CM`] apart while it fits (36 droids do) and closer beyond, always at
    /// least [`EDGE_CM`] from the walls of the shared room (the default room every model has).
    pub fn origins(n: usize) -> Vec<(f32, f32)> {
        let room = super::SimConfig::default().room_cm;
        let usable = ((room.0.min(room.1)) - 2.0 * EDGE_CM).max(0.0);
        let fits = (usable / SPACING_CM) as usize + 1;
        let cols = if n <= fits {
            n.max(1)
        } else {
            (n as f64).sqrt().ceil() as usize
        };
        let rows = n.div_ceil(cols).max(1);
        let widest = cols.max(rows);
        let spacing = if widest > 1 {
            SPACING_CM.min(usable / (widest - 1) as f32)
        } else {
            SPACING_CM
        };
        let mid_x = (cols - 1) as f32 / 2.0;
        let mid_y = (rows - 1) as f32 / 2.0;
        (0..n)
            .map(|i| {
                let (r, c) = (i / cols, i % cols);
                ((c as f32 - mid_x) * spacing, (mid_y - r as f32) * spacing)
            })
            .collect()
    }

    /// Every droid's position in room coordinates (tests, the map of all droids).
    pub fn positions(&self) -> Vec<(f32, f32)> {
        self.lock().iter().map(|o| (o.x, o.y)).collect()
    }
}

impl Place {
    /// The droid moved to (`x`, `y`) (room coordinates) with velocity (`vx`, `vy`). When that
    /// runs it into another droid it stops touching it: the contact is returned and the other
    /// droid is told it was hit.
    pub fn moved(&self, x: f32, y: f32, vx: f32, vy: f32) -> Option<Contact> {
        let mut all = self.room.lock();
        let my_radius = all.get(self.id)?.radius;
        let mut pos = (x, y);
        let mut contact = None;
        for (i, o) in all.iter_mut().enumerate() {
            if i == self.id {
                continue;
            }
            let (dx, dy) = (o.x - pos.0, o.y - pos.1);
            let dist = (dx * dx + dy * dy).sqrt();
            let touch = my_radius + o.radius;
            // Only moving toward the other counts (two droids apart may drive off).
            if dist >= touch || dx * vx + dy * vy <= 0.0 {
                continue;
            }
            let (nx, ny) = if dist > 1e-4 {
                (dx / dist, dy / dist)
            } else {
                let v = (vx * vx + vy * vy).sqrt().max(1e-4);
                (vx / v, vy / v)
            };
            pos = (o.x - nx * touch, o.y - ny * touch);
            let speed = (vx * nx + vy * ny).abs();
            o.hit = Some(Hit {
                dx: -nx,
                dy: -ny,
                speed,
            });
            contact = Some(Contact {
                x: pos.0,
                y: pos.1,
                nx,
                ny,
            });
        }
        if let Some(m) = all.get_mut(self.id) {
            m.x = pos.0;
            m.y = pos.1;
        }
        contact
    }

    /// A hit by another droid since the last call.
    pub fn take_hit(&self) -> Option<Hit> {
        self.room.lock().get_mut(self.id).and_then(|o| o.hit.take())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn running_into_another_stops_touching_it_and_tells_it() {
        let room = SharedRoom::new();
        let a = room.place((-30.0, 0.0), 10.0);
        let b = room.place((30.0, 0.0), 10.0);
        // Far apart: nothing.
        assert_eq!(a.moved(0.0, 0.0, 50.0, 0.0), None);
        // a reaches into b: it stops at 20 cm from b's centre.
        let c = a.moved(15.0, 0.0, 50.0, 0.0).expect("a contact");
        assert!((c.x - 10.0).abs() < 1e-3 && c.nx > 0.99, "{c:?}");
        let hit = b.take_hit().expect("b was hit");
        assert!(hit.dx < -0.99 && (hit.speed - 50.0).abs() < 1e-3, "{hit:?}");
        assert_eq!(b.take_hit(), None, "a hit is reported once");
        assert_eq!(a.take_hit(), None);
        // Driving away from it is free.
        assert_eq!(a.moved(9.0, 0.0, -50.0, 0.0), None);
        assert_eq!(room.positions(), vec![(9.0, 0.0), (30.0, 0.0)]);
    }

    #[test]
    fn origins_are_centred() {
        assert_eq!(SharedRoom::origins(1), vec![(0.0, 0.0)]);
        assert_eq!(
            SharedRoom::origins(3),
            vec![(-SPACING_CM, 0.0), (0.0, 0.0), (SPACING_CM, 0.0)]
        );
    }

    #[test]
    fn every_fleet_starts_inside_the_room_and_apart() {
        let half = crate::sim::SimConfig::default().room_cm.0 / 2.0 - EDGE_CM;
        for n in 1..=64 {
            let o = SharedRoom::origins(n);
            assert_eq!(o.len(), n);
            for p in &o {
                assert!(
                    p.0.abs() <= half + 1e-3 && p.1.abs() <= half + 1e-3,
                    "{n}: {p:?}"
                );
            }
            let closest = o
                .iter()
                .enumerate()
                .flat_map(|(i, a)| o[i + 1..].iter().map(move |b| (a.0 - b.0).hypot(a.1 - b.1)))
                .fold(f32::MAX, f32::min);
            // 60 cm apart as far as 36 droids; never touching beyond (radius 10 cm each).
            let want = if n <= 36 { SPACING_CM - 1e-3 } else { 25.0 };
            assert!(closest >= want, "{n} droids: {closest} cm apart");
        }
    }
}
