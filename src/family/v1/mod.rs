//! Sphero API v1 behind the family seam (BB-8, SPRK+, Ollie).
//!
//! Differences from v2 that this file absorbs: a response echoes only the SEQ (no DID/CID),
//! so its payload can be read only with the request's schema; the droid has no Wake command
//! (it wakes at the GATT level, `droid-facts.md` §4) and no dome, legs, sounds or
//! animations; Roll has no reverse flag, so reversing rolls toward the opposite heading.

pub mod gatt;
pub mod named;
pub mod read;

use super::{
    Codec, Command, DroidError, Explained, Family, Incoming, Key, Packet, PacketKind, ReadOption,
    ReadOptions, Reader,
};
use crate::family::setup::SetupOptions;
use crate::family::stream::{
    BLE_SENSOR_NOTIFICATIONS_PER_S, STANDARD_RATES, SensorGroup, SensorSet, StreamCaps, StreamPlan,
};
use crate::family::{RecordedDrive, RecordedLeds};
use crate::model::{Model, Protocol};
use crate::protocol::decode::ErrorKind;
use crate::protocol::v1::{self, Decoder, Source, StreamingConfig, cmd};
use crate::script::{Action, LedGroup};
use crate::tuning::CollisionConfig;
use crate::units::Heading;

/// The v1 family.
pub struct V1;

/// The v1 sample clock: rate = 400 / N Hz (`droid-facts.md` §4).
pub fn divisor_for(interval_ms: u16) -> u16 {
    ((interval_ms as u32 * 400) / 1000).clamp(1, u16::MAX as u32) as u16
}

/// A v1 connection's codec: the decoder reads the droid's side of the stream (responses
/// and async messages; a command would begin with the same `FF FF`).
pub struct V1Codec {
    decoder: Decoder,
    streaming: StreamingConfig,
    /// The droid's model when known: Ollie's samples are turned to the room's axes.
    model: Option<Model>,
}

impl V1Codec {
    pub fn new() -> Self {
        V1Codec {
            decoder: Decoder::new(Source::Droid),
            streaming: StreamingConfig::default(),
            model: None,
        }
    }

    /// The codec of a connection to `model`: an Ollie's locator and velocity are read in
    /// the room's axes, as spherov2 reads them (`v1::sensor::rotated_axes`).
    pub fn for_model(model: Model) -> Self {
        V1Codec {
            model: Some(model),
            ..V1Codec::new()
        }
    }
}

impl Default for V1Codec {
    fn default() -> Self {
        Self::new()
    }
}

fn v1_of(c: &Command) -> v1::Command {
    match c {
        Command::V1(c) => c.clone(),
        other => {
            tracing::error!(command = %other.name(), "a non-v1 command reached the v1 codec");
            cmd::ping()
        }
    }
}

/// Explain a v1 packet; `request` gives the schema of a response's payload.
pub fn explain(
    p: &v1::Packet,
    streaming: Option<&StreamingConfig>,
    request: Option<&Command>,
) -> Explained {
    let d = v1::describe(p, streaming, request.and_then(Command::as_v1));
    let (kind, did, seq, error) = match p {
        v1::Packet::Command(c) => (PacketKind::Command, Some(c.did), Some(c.seq), None),
        v1::Packet::Response(r) => (
            PacketKind::Response,
            request.map(Command::did),
            Some(r.seq),
            (!r.mrsp.is_success()).then_some(DroidError::V1(r.mrsp)),
        ),
        v1::Packet::Async(_) => (PacketKind::Notification, None, None, None),
    };
    let label = d.name.map(String::from).unwrap_or_else(|| match p {
        v1::Packet::Command(c) => format!("0x{:02X}/0x{:02X}", c.did, c.cid),
        v1::Packet::Response(_) => match request {
            Some(r) => format!("{} (answer)", r.name()),
            None => "response".into(),
        },
        v1::Packet::Async(a) => format!("async 0x{:02X}", a.id_code),
    });
    Explained {
        kind,
        label,
        known: d.name.is_some(),
        fields: d.fields,
        problem: d.problem,
        error,
        did,
        seq,
    }
}

/// A sample of `model` in the room's axes (an Ollie's turned back; the others as they came).
fn room_axes(model: Option<Model>, n: v1::Notification) -> v1::Notification {
    match (n, model) {
        (v1::Notification::Sensors(mut s), Some(model)) => {
            v1::sensor::from_droid_axes(model, &mut s.values);
            v1::Notification::Sensors(s)
        }
        (n, _) => n,
    }
}

impl Codec for V1Codec {
    fn protocol(&self) -> Protocol {
        Protocol::SpheroV1
    }

    /// v1 responses echo only the SEQ.
    fn key(&self, _c: &Command, seq: u8) -> Key {
        (0, 0, seq)
    }

    fn encode(&mut self, c: &Command, seq: u8, want_response: bool) -> (Vec<u8>, Packet) {
        let c = v1_of(c);
        if (c.did, c.cid) == (0x02, 0x11)
            && let Some(s) = StreamingConfig::from_command_data(&c.data)
        {
            self.streaming = s;
        }
        // Every command resets the droid's inactivity timer: driving keeps it awake.
        let packet = v1::CommandPacket::new(c.did, c.cid, seq, c.data.clone())
            .with_options(want_response, true);
        let p = v1::Packet::Command(packet);
        // The catalogue's payloads are far below the 254-byte DLEN limit; a command that is
        // not is written as nothing (and logged) rather than as a broken frame.
        let wire = p.encode().unwrap_or_else(|e| {
            tracing::error!(error = %e, "v1 command too long to frame");
            Vec::new()
        });
        (wire, Packet::V1(p))
    }

    fn reset_stream(&mut self) {
        self.decoder = Decoder::new(Source::Droid);
    }

    fn feed(&mut self, bytes: &[u8], out: &mut Vec<Incoming>) {
        let model = self.model;
        for r in self.decoder.feed(bytes) {
            out.push(match r {
                Err(e) => Incoming::Error(read::seam_error(e)),
                Ok(v1::Packet::Response(r)) => Incoming::Response {
                    key: (0, 0, r.seq),
                    error: (!r.mrsp.is_success()).then_some(DroidError::V1(r.mrsp)),
                    packet: Packet::V1(v1::Packet::Response(r)),
                },
                Ok(v1::Packet::Async(a)) => {
                    // Fix: sensor data that arrives before this connection has written Set
                    // Data Streaming (the droid keeps streaming across a reconnect until the
                    // setup reconfigures it), or after streaming was turned off, cannot be
                    // laid out. It used to be reported as a malformed notification, so every
                    // reconnect to a streaming droid counted errors. It is now read as no
                    // samples (the packet is still logged, raw).
                    let unknown_layout =
                        a.id_code == v1::catalog::id::SENSOR_DATA && !self.streaming.is_streaming();
                    let notifications = match v1::decode_async(&a, &self.streaming) {
                        _ if unknown_layout => Vec::new(),
                        Ok(ns) => ns.into_iter().map(|n| Ok(room_axes(model, n))).collect(),
                        Err(e) => vec![Err(e)],
                    };
                    Incoming::Async {
                        notifications,
                        packet: Packet::V1(v1::Packet::Async(a)),
                    }
                }
                Ok(p @ v1::Packet::Command(_)) => Incoming::Stray(Packet::V1(p)),
            });
        }
    }

    fn explain(&self, p: &Packet, request: Option<&Command>) -> Explained {
        match p {
            // Without a layout, sensor data is shown as its raw values.
            Packet::V1(p) => explain(
                p,
                self.streaming.is_streaming().then_some(&self.streaming),
                request,
            ),
            other => super::explain_foreign(other),
        }
    }
}

impl Family for V1 {
    fn protocol(&self) -> Protocol {
        Protocol::SpheroV1
    }

    fn name(&self) -> &'static str {
        "v1"
    }

    fn display_name(&self) -> &'static str {
        "Sphero API v1"
    }

    fn sop(&self) -> u8 {
        v1::packet::SOP1
    }

    fn representative(&self) -> Model {
        Model::first_speaking(self.protocol())
    }

    fn error_kinds(&self) -> &'static [ErrorKind] {
        &v1::ERROR_KINDS
    }

    fn read_options(&self) -> &'static [ReadOption] {
        &[
            ReadOption::Side,
            ReadOption::SensorMask,
            ReadOption::Mask2,
            ReadOption::Frames,
            ReadOption::Request,
        ]
    }

    fn reader(&self, opts: &ReadOptions) -> Result<Box<dyn Reader>, super::error::ReadError> {
        Ok(Box::new(read::V1Reader::new(opts)?))
    }

    fn side_reader(&self, side: super::Side, _whole_values: bool) -> Box<dyn Reader> {
        Box::new(read::V1Reader::for_side(side))
    }

    fn gatt_profile(&self, model: Model) -> crate::gatt::GattProfile {
        gatt::profile(model)
    }

    fn encode_named(
        &self,
        name: &str,
        params: Vec<(String, String)>,
    ) -> Result<Vec<u8>, super::error::NamedError> {
        named::encode(name, params)
    }

    fn encode_names(&self) -> Vec<(String, &'static str)> {
        named::names()
    }

    fn list(&self, filter: Option<&str>, out: &mut dyn std::io::Write) -> std::io::Result<usize> {
        named::list(filter, out)
    }

    fn codec(&self) -> Box<dyn Codec> {
        Box::new(V1Codec::new())
    }

    fn codec_for(&self, model: Model) -> Box<dyn Codec> {
        Box::new(V1Codec::for_model(model))
    }

    /// v1 droids wake at the GATT level (the wake sequence of `droid-facts.md` §4).
    fn wake(&self) -> Option<Command> {
        None
    }

    fn ping(&self) -> Command {
        cmd::ping().into()
    }

    fn sleep(&self) -> Option<Command> {
        Some(cmd::sleep(0, 0, 0).into())
    }

    /// Set Raw Motors (0x02/0x33), as spherov2's `raw_motor` drives the API v1 robots.
    fn tank(&self, left: i16, right: i16) -> Option<Command> {
        Some(raw_motors(left, right))
    }

    /// v1's own: stabilisation is Set Stabilization on or off.
    fn lower(
        &self,
        model: Model,
        intent: &super::intent::Intent,
    ) -> Result<Vec<Command>, super::intent::Unsupported> {
        match intent {
            super::intent::Intent::Stabilization(on) => {
                Ok(vec![cmd::set_stabilization(*on).into()])
            }
            _ => super::intent::lower_common(self, model, intent),
        }
    }

    /// Roll has no reverse flag: backing up is rolling toward the opposite heading.
    fn drive(&self, speed: u8, heading: Heading, reverse: bool) -> Command {
        let heading = if reverse { heading.reversed() } else { heading };
        cmd::roll(speed, heading, v1::RollState::Go).into()
    }

    /// Roll, and Set Raw Motors (Sphero Edu's `rawMotor`, a mission's `tank`).
    fn is_drive(&self, c: &Command) -> bool {
        matches!(c, Command::V1(c) if matches!((c.did, c.cid), (0x02, 0x30) | (0x02, 0x33)))
    }

    /// Roll state 0 is the API's stop; the heading is kept so the droid does not turn. After
    /// raw motors, both motors off (the control system let go of them; a Roll alone would
    /// ask a control system that is off).
    fn stop_after(&self, last: Option<&Command>) -> Command {
        if let Some(Command::V1(c)) = last
            && (c.did, c.cid) == (0x02, 0x33)
        {
            return raw_motors(0, 0);
        }
        let heading = match last {
            Some(Command::V1(c)) if (c.did, c.cid) == (0x02, 0x30) && c.data.len() >= 3 => {
                u16::from_be_bytes([c.data[1], c.data[2]])
            }
            _ => 0,
        };
        cmd::roll(0, Heading::wrapped(heading as f64), v1::RollState::Stop).into()
    }

    /// The main RGB LED (script group `front`) and the blue back LED (`back`, brightness).
    fn led(&self, _model: Model, action: &Action) -> Option<Command> {
        match *action {
            Action::LedRgb(LedGroup::Front, [r, g, b]) => {
                Some(cmd::set_rgb_led(r, g, b, false).into())
            }
            // Fix: scripts only write `led back R G B` (the parser has no brightness form for
            // `back`), so a v1 back-LED line was refused as "no such LED". The back LED is a
            // single blue LED: it takes the brightest channel as its brightness.
            Action::LedRgb(LedGroup::Back, [r, g, b]) => {
                Some(cmd::set_back_led(r.max(g).max(b)).into())
            }
            Action::LedBrightness(LedGroup::Back, b) => Some(cmd::set_back_led(b).into()),
            _ => None,
        }
    }

    fn battery_request(&self) -> Option<Command> {
        Some(cmd::get_power_state().into())
    }

    /// Get Power State: record version, state, battery voltage u16 in 1/100 V, …
    fn battery_volts(&self, response: &[u8]) -> Option<f32> {
        let hi = *response.get(2)?;
        let lo = *response.get(3)?;
        Some(u16::from_be_bytes([hi, lo]) as f32 / 100.0)
    }

    /// Set Temporary Option Flags bit 0: stop on disconnect (DID 02h, CID 37h).
    fn fail_safe(&self) -> Option<Command> {
        Some(cmd::set_temporary_option_flags(v1::catalog::TEMP_OPTION_STOP_ON_DISCONNECT).into())
    }

    fn setup(&self, model: Model, opts: &SetupOptions) -> Vec<Command> {
        let mut out: Vec<Command> = vec![
            // Stop on disconnect first: from here on a dropped link stops the droid.
            cmd::set_temporary_option_flags(v1::catalog::TEMP_OPTION_STOP_ON_DISCONNECT).into(),
            // The first answer proves the link; it also resets the inactivity timer.
            cmd::ping().into(),
            cmd::set_stabilization(true).into(),
        ];
        out.extend(self.collision_detection(&opts.collision));
        let plan = opts.stream_plan(model);
        if plan.is_on() {
            out.extend(self.streaming(model, &plan));
        }
        out.push(cmd::set_power_notification(true).into());
        out
    }

    fn aim_begin(&self, _model: Model) -> Option<Vec<Command>> {
        Some(vec![
            cmd::set_back_led(255).into(),
            // Stabilised, a Roll at speed 0 turns the droid in place.
            cmd::set_stabilization(true).into(),
        ])
    }

    fn aim_end(&self, _model: Model) -> Vec<Command> {
        vec![
            // Set Heading 0: where the droid faces now is heading 0.
            cmd::set_heading(Heading::default()).into(),
            cmd::set_back_led(0).into(),
        ]
    }

    fn stream_caps(&self, _model: Model) -> Option<StreamCaps> {
        Some(StreamCaps {
            groups: SensorSet::of(&[
                SensorGroup::Attitude,
                SensorGroup::Accelerometer,
                SensorGroup::Gyro,
                SensorGroup::Locator,
                SensorGroup::Velocity,
            ]),
            // 400/N Hz: N = 400, 40, 20, 8, 4 make the standard rates exactly.
            rates: &STANDARD_RATES,
            notifications_per_s: BLE_SENSOR_NOTIFICATIONS_PER_S,
        })
    }

    /// An async packet `FF FE 03 DLEN(2) … CHK` around one i16 per value, one frame each.
    fn stream_sample_bytes(&self, sensors: SensorSet) -> usize {
        6 + 2 * stream_config(sensors, 1).values_per_frame()
    }

    /// Set Data Streaming with the groups' MASK and MASK2 at 400/N Hz, one frame per packet;
    /// off is N = 0 with empty masks (`droid-facts.md` §4: MASK 0 = off).
    fn streaming(&self, _model: Model, plan: &StreamPlan) -> Vec<Command> {
        let s = if plan.is_on() {
            stream_config(plan.sensors, divisor_for(plan.interval_ms))
        } else {
            StreamingConfig::default()
        };
        vec![
            cmd::set_data_streaming(
                s.n,
                s.m.max(1),
                s.mask,
                0,
                (s.mask2 != 0).then_some(s.mask2),
            )
            .into(),
        ]
    }

    /// Configure Collision Detection in the catalogue's order `[method, Xt, Xspd, Yt, Yspd,
    /// dead]` (the Sphero API 1.50 order, `droid-facts.md` §4); v1 reports collisions once
    /// configured.
    fn collision_detection(&self, c: &CollisionConfig) -> Vec<Command> {
        vec![
            cmd::configure_collision_detection(
                c.method(),
                c.x_threshold,
                c.x_speed,
                c.y_threshold,
                c.y_speed,
                c.dead_time_units(),
            )
            .into(),
        ]
    }

    /// Roll `[speed, heading u16, state]`; reversing is rolling toward the opposite heading,
    /// so a capture shows a heading, never a reverse.
    fn read_drive(&self, c: &Command) -> Option<RecordedDrive> {
        let Command::V1(c) = c else { return None };
        match (c.did, c.cid, c.data.as_slice()) {
            (0x02, 0x30, [speed, h0, h1, state]) => Some(RecordedDrive {
                speed: if *state == 0 { 0 } else { *speed },
                heading: Heading::wrapped(u16::from_be_bytes([*h0, *h1]) as f64),
                reverse: false,
                steer: None,
            }),
            _ => None,
        }
    }

    fn read_leds(&self, _model: Model, c: &Command) -> Option<RecordedLeds> {
        let Command::V1(c) = c else { return None };
        match (c.did, c.cid, c.data.as_slice()) {
            (0x02, 0x20, [r, g, b, ..]) => Some(RecordedLeds {
                main: Some([*r, *g, *b]),
                back: None,
            }),
            (0x02, 0x21, [b]) => Some(RecordedLeds {
                main: None,
                back: Some(*b),
            }),
            _ => None,
        }
    }
}

/// The masks of `sensors` at divisor `n`, one frame per packet, forever.
fn stream_config(sensors: SensorSet, n: u16) -> StreamingConfig {
    use crate::protocol::v1::sensor::mask;
    let mut s = StreamingConfig {
        n,
        m: 1,
        ..StreamingConfig::default()
    };
    for g in sensors.iter() {
        match g {
            SensorGroup::Attitude => s.mask |= mask::IMU,
            SensorGroup::Accelerometer => s.mask |= mask::ACCEL,
            SensorGroup::Gyro => s.mask |= mask::GYRO,
            SensorGroup::Locator => s.mask2 |= mask::LOCATOR,
            SensorGroup::Velocity => s.mask2 |= mask::VELOCITY,
            SensorGroup::HeadAngle => {}
        }
    }
    s
}

/// Set Raw Motors for sides at `left`/`right` in −255..=255: forward, reverse or off
/// (spherov2's `RawMotorModes`).
fn raw_motors(left: i16, right: i16) -> Command {
    let side = |v: i16| match v {
        0 => (v1::MotorMode::Off, 0),
        v if v > 0 => (v1::MotorMode::Forward, v.min(255) as u8),
        v => (v1::MotorMode::Reverse, v.unsigned_abs().min(255) as u8),
    };
    let ((lm, lp), (rm, rp)) = (side(left), side(right));
    cmd::set_raw_motors(lm, lp, rm, rp).into()
}
