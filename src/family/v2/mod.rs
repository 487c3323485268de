//! Sphero API v2 behind the family seam (R2-D2, R2-Q5, BB-9E).

pub mod gatt;
pub mod named;
pub mod read;
pub mod robots;

use super::{
    Codec, Command, DroidError, Explained, Family, Incoming, Key, Packet, PacketKind, ReadOption,
    ReadOptions, Reader,
};
use crate::family::intent::{self, Intent, Unsupported};
use crate::family::setup::SetupOptions;
use crate::family::stream::{
    BLE_SENSOR_NOTIFICATIONS_PER_S, STANDARD_RATES, SensorGroup, SensorSet, StreamCaps, StreamPlan,
};
use crate::family::{RecordedDrive, RecordedLeds};
use crate::model::{Caps, Model, Protocol};
use crate::protocol::decode::ErrorKind;
use crate::protocol::v2::catalog::targets;
use crate::protocol::v2::sensor::StreamingConfig;
use crate::protocol::v2::wire::{
    AudioMode, Bytes, CollisionMethod, DriveFlags, LegAction, Mask, StabilizationIndex,
};
use crate::protocol::v2::{self, Decoder, Flags, Kind, Notification, cmd, describe};
use crate::script::{Action, LedGroup};
use crate::tuning::CollisionConfig;
use crate::units::{HeadAngle, Heading};

/// The v2 family.
pub struct V2;

/// The v2 fail-safe: stop when no drive command came for this long.
pub const FAIL_SAFE_TIMEOUT_MS: u16 = 2000;

/// A v2 connection's codec: the streaming decoder and the masks in effect.
pub struct V2Codec {
    decoder: Decoder,
    streaming: StreamingConfig,
    /// The robot on the connection: BOLT and RVR have processors to address.
    model: Option<Model>,
    /// What the droid was told to stream through the streaming service (RVR).
    service: crate::protocol::v2::stream::ServiceConfig,
}

impl V2Codec {
    pub fn new() -> Self {
        V2Codec {
            decoder: Decoder::new(),
            streaming: StreamingConfig::default(),
            model: None,
            service: Default::default(),
        }
    }

    /// The codec of a connection to `model`: commands without a target get the one of the
    /// processor that has them (`catalog::targets`).
    pub fn for_model(model: Model) -> Self {
        V2Codec {
            model: Some(model),
            ..V2Codec::new()
        }
    }

    /// Track what the droid will stream.
    fn snoop(&mut self, c: &v2::Command) {
        match (c.did, c.cid, c.data.as_slice()) {
            (0x18, 0x00, [i0, i1, _count, m @ ..]) if m.len() == 4 => {
                self.streaming.interval_ms = u16::from_be_bytes([*i0, *i1]);
                self.streaming.mask = u32::from_be_bytes([m[0], m[1], m[2], m[3]]);
            }
            (0x18, 0x0C, m) if m.len() == 4 => {
                self.streaming.ext_mask = u32::from_be_bytes([m[0], m[1], m[2], m[3]]);
            }
            (0x18, 0x39..=0x3C, _) => self.service.snoop(c),
            _ => {}
        }
    }
}

impl Default for V2Codec {
    fn default() -> Self {
        Self::new()
    }
}

impl V2Codec {
    /// The command as it goes on the wire to this connection's robot: addressed to the
    /// processor that has it (BOLT, RVR), and Core's Ping as API and Shell's Echo on the
    /// newer robots, which have no Core device (spherov2.py pings them with 0x10/0x00).
    fn wire_form(&self, c: &Command) -> v2::Command {
        let mut c = v2_of(c);
        let Some(model) = self.model else {
            return c;
        };
        if robots::has_no_core(model) && (c.did, c.cid) == (0x00, 0x01) {
            c = cmd::echo(Bytes(Vec::new()));
        }
        if c.target.is_none() {
            c.target = targets::addressed(model, c.did, c.cid).map(|p| p.target_id());
        }
        c
    }
}

/// The v2 part of a family command. Commands of another family cannot be framed here; the
/// session never mixes families, so this only guards against a programming error.
fn v2_of(c: &Command) -> v2::Command {
    match c {
        Command::V2(c) => c.clone(),
        other => {
            tracing::error!(command = %other.name(), "a non-v2 command reached the v2 codec");
            cmd::ping()
        }
    }
}

/// Explain a v2 packet with the catalogue and the masks in effect.
pub fn explain(p: &v2::Packet, streaming: Option<&StreamingConfig>) -> Explained {
    let d = describe(p, streaming);
    let kind = match d.kind {
        Kind::Command => PacketKind::Command,
        Kind::Response => PacketKind::Response,
        Kind::Notification => PacketKind::Notification,
    };
    Explained {
        kind,
        label: d.label(p),
        known: d.name.is_some(),
        fields: d.fields,
        problem: d.problem,
        error: p.err.filter(|e| !e.is_success()).map(DroidError::V2),
        did: Some(p.did),
        seq: (kind != PacketKind::Notification).then_some(p.seq),
    }
}

impl Codec for V2Codec {
    fn protocol(&self) -> Protocol {
        Protocol::SpheroV2
    }

    fn key(&self, c: &Command, seq: u8) -> Key {
        let c = self.wire_form(c);
        (c.did, c.cid, seq)
    }

    fn encode(&mut self, c: &Command, seq: u8, want_response: bool) -> (Vec<u8>, Packet) {
        let c = self.wire_form(c);
        self.snoop(&c);
        let mut packet = c.to_packet(seq);
        if !want_response {
            packet.flags.remove(Flags::REQUESTS_RESPONSE);
        }
        (packet.encode(), Packet::V2(packet))
    }

    fn reset_stream(&mut self) {
        self.decoder = Decoder::new();
    }

    fn feed(&mut self, bytes: &[u8], out: &mut Vec<Incoming>) {
        for r in self.decoder.feed(bytes) {
            out.push(match r {
                Err(e) => Incoming::Error(read::seam_error(e)),
                Ok(p) if p.is_response() => Incoming::Response {
                    key: (p.did, p.cid, p.seq),
                    error: p.err.filter(|e| !e.is_success()).map(DroidError::V2),
                    packet: Packet::V2(p),
                },
                Ok(p) if p.is_notification() => Incoming::Async {
                    notifications: vec![Notification::decode_with(
                        &p,
                        &self.streaming,
                        &self.service,
                    )],
                    packet: Packet::V2(p),
                },
                Ok(p) => Incoming::Stray(Packet::V2(p)),
            });
        }
    }

    fn explain(&self, p: &Packet, _request: Option<&Command>) -> Explained {
        match p {
            // Without masks, sensor data is shown as its raw values (as v1 does).
            Packet::V2(p) => {
                let mut e = explain(
                    p,
                    (self.streaming.mask != 0 || self.streaming.ext_mask != 0)
                        .then_some(&self.streaming),
                );
                // RVR's streaming-service data, named by what this connection configured
                // (issue 30 point 7: not `token=1 data=[80 00 …]`).
                if e.kind == PacketKind::Notification
                    && (p.did, p.cid) == (0x18, 0x3D)
                    && !self.service.slots.is_empty()
                {
                    let processor = p.sid.and_then(targets::Processor::of_id);
                    match v2::stream::decode(&self.service, processor, &p.data) {
                        Ok(s) => {
                            e.fields = Some(s.fields());
                            e.problem = None;
                        }
                        Err(err) => {
                            e.fields = None;
                            e.problem = Some(err.to_string());
                        }
                    }
                }
                e
            }
            other => super::explain_foreign(other),
        }
    }
}

impl Family for V2 {
    fn protocol(&self) -> Protocol {
        Protocol::SpheroV2
    }

    fn name(&self) -> &'static str {
        "v2"
    }

    fn display_name(&self) -> &'static str {
        "Sphero API v2"
    }

    fn sop(&self) -> u8 {
        v2::packet::SOP
    }

    fn representative(&self) -> Model {
        Model::first_speaking(self.protocol())
    }

    fn error_kinds(&self) -> &'static [ErrorKind] {
        &v2::ERROR_KINDS
    }

    fn read_options(&self) -> &'static [ReadOption] {
        &[ReadOption::SensorMask, ReadOption::ExtMask]
    }

    fn reader(&self, opts: &ReadOptions) -> Result<Box<dyn Reader>, super::error::ReadError> {
        Ok(Box::new(read::V2Reader::new(opts)))
    }

    fn side_reader(&self, side: super::Side, whole_values: bool) -> Box<dyn Reader> {
        let opts = ReadOptions {
            side: Some(side),
            whole_values,
            ..ReadOptions::default()
        };
        Box::new(read::V2Reader::new(&opts))
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
        Box::new(V2Codec::new())
    }

    fn codec_for(&self, model: Model) -> Box<dyn Codec> {
        Box::new(V2Codec::for_model(model))
    }

    fn wake(&self) -> Option<Command> {
        Some(cmd::wake().into())
    }

    fn ping(&self) -> Command {
        cmd::ping().into()
    }

    fn sleep(&self) -> Option<Command> {
        Some(cmd::sleep().into())
    }

    fn drive(&self, speed: u8, heading: Heading, reverse: bool) -> Command {
        // Reverse = speed with BACKWARD, and reference clients add 180° to the heading
        // (`droid-facts.md` §2): `heading` is the direction the droid faces.
        let (heading, flags) = if reverse {
            (heading.reversed(), DriveFlags::BACKWARD)
        } else {
            (heading, DriveFlags::empty())
        };
        cmd::drive_with_heading(speed, heading, flags).into()
    }

    fn is_drive(&self, c: &Command) -> bool {
        matches!(c, Command::V2(c) if matches!((c.did, c.cid), (0x16, 0x07) | (0x16, 0x01)))
    }

    fn stop_after(&self, last: Option<&Command>) -> Command {
        // Tracks stop with both motors off.
        if let Some(Command::V2(c)) = last
            && (c.did, c.cid) == (0x16, 0x01)
        {
            return robots::tank(0, 0);
        }
        let mut stop = match last {
            Some(Command::V2(c)) if (c.did, c.cid) == (0x16, 0x07) => c.clone(),
            _ => cmd::drive_with_heading(0, Heading::default(), DriveFlags::empty()),
        };
        if let Some(speed) = stop.data.first_mut() {
            *speed = 0;
        }
        stop.into()
    }

    fn head(&self, angle: HeadAngle) -> Option<Command> {
        Some(cmd::set_head_position(angle).into())
    }

    fn stance(&self, action: LegAction) -> Option<Command> {
        Some(cmd::perform_leg_action(action).into())
    }

    fn get_stance(&self) -> Option<Command> {
        Some(cmd::get_leg_action().into())
    }

    fn animation(&self, model: Model, id: u16) -> Option<Command> {
        model
            .plays_animations()
            .then(|| cmd::play_animation(id).into())
    }

    fn sound(&self, model: Model, id: u16) -> Option<Command> {
        model
            .plays_animations()
            .then(|| cmd::play_audio_file(id, AudioMode::Immediate).into())
    }

    /// R2 bits 0..2 front RGB, 3 logic, 4..6 back RGB, 7 holo; BB-9E 0..2 body RGB,
    /// 3 aiming, 4 head (`droid-facts.md` §2).
    fn led(&self, model: Model, action: &Action) -> Option<Command> {
        if let Some(c) = robots::led(model, action) {
            return c;
        }
        let r2 = model.has_legs();
        let (mask, values): (u32, Vec<u8>) = match *action {
            Action::LedRgb(LedGroup::Front, rgb) => (0x0007, rgb.to_vec()),
            Action::LedRgb(LedGroup::Back, rgb) if r2 => (0x0070, rgb.to_vec()),
            Action::LedBrightness(LedGroup::Logic, b) => (0x0008, vec![b]),
            Action::LedBrightness(LedGroup::Holo, b) => (if r2 { 0x0080 } else { 0x0010 }, vec![b]),
            // BB-9E's "back" light is its aiming LED (bit 3); scripts give it as R G B.
            Action::LedBrightness(LedGroup::Back, b) if !r2 => (0x0008, vec![b]),
            Action::LedRgb(LedGroup::Back, [r, g, b]) if !r2 => (0x0008, vec![r.max(g).max(b)]),
            _ => return None,
        };
        Some(cmd::set_all_leds_with_16_bit_mask(Mask(mask), Bytes(values)).into())
    }

    fn battery_request(&self) -> Option<Command> {
        Some(cmd::get_battery_voltage().into())
    }

    fn battery_volts(&self, response: &[u8]) -> Option<f32> {
        crate::telemetry::battery_volts(response)
    }

    fn battery_request_for(&self, model: Model) -> Option<Command> {
        robots::battery_request(model).or_else(|| self.battery_request())
    }

    fn battery_volts_for(&self, model: Model, response: &[u8]) -> Option<f32> {
        match robots::battery_request(model) {
            Some(_) => robots::battery_volts(response),
            None => self.battery_volts(response),
        }
    }

    /// Set Custom Control System Timeout (DID 16h, CID 22h): the droid stops by itself when
    /// drive commands stop for this long. Comfortably above the slowest drive re-send (the
    /// missions' 0.5 s heartbeat; the app re-sends at its control rate).
    fn fail_safe(&self) -> Option<Command> {
        Some(cmd::set_custom_control_system_timeout(FAIL_SAFE_TIMEOUT_MS).into())
    }

    fn setup(&self, model: Model, opts: &SetupOptions) -> Vec<Command> {
        let mut out = vec![
            cmd::wake(),
            cmd::set_custom_control_system_timeout(FAIL_SAFE_TIMEOUT_MS),
        ];
        if model.has_legs() && opts.tripod {
            out.push(cmd::perform_leg_action(LegAction::Tripod));
        }
        if model.has_dome() {
            out.push(cmd::set_head_position(HeadAngle::clamped(0.0)));
        }
        let mut out: Vec<Command> = out.into_iter().map(Command::from).collect();
        out.extend(self.collision_detection(&opts.collision));
        let plan = opts.stream_plan(model);
        if plan.is_on() {
            out.extend(self.streaming(model, &plan));
        }
        out.push(cmd::enable_battery_state_changed_notify(true).into());
        out.push(cmd::enable_battery_voltage_state_change_notify(true).into());
        // RVR's motor notifications and colour detection (its streaming is `streaming`).
        out.extend(robots::setup_extra(model, 0));
        out
    }

    /// BB-9E rolls like BB-8 and has an aiming light (LED bit 3); R2 has legs and no aim
    /// light, so it drives without aiming.
    fn aim_begin(&self, model: Model) -> Option<Vec<Command>> {
        if let Some(cmds) = robots::aim_begin(model) {
            return Some(cmds);
        }
        if model.has_legs() {
            return None;
        }
        Some(vec![
            cmd::set_all_leds_with_16_bit_mask(Mask(0x0008), Bytes(vec![255])).into(),
            // Keep stabilisation on so the body turns in place without rolling.
            cmd::set_stabilization(StabilizationIndex::Full).into(),
        ])
    }

    fn aim_end(&self, model: Model) -> Vec<Command> {
        if let Some(cmds) = robots::aim_end(model) {
            return cmds;
        }
        vec![
            cmd::reset_yaw().into(),
            cmd::set_all_leds_with_16_bit_mask(Mask(0x0008), Bytes(vec![0])).into(),
        ]
    }

    /// v2's own: stabilisation, BOLT's matrix (and its main light) and compass, BOLT's and
    /// RVR's infrared.
    fn lower(&self, model: Model, intent: &Intent) -> Result<Vec<Command>, Unsupported> {
        match intent {
            Intent::Stabilization(on) => Ok(vec![
                cmd::set_stabilization(if *on {
                    StabilizationIndex::Full
                } else {
                    StabilizationIndex::None
                })
                .into(),
            ]),
            Intent::Matrix(m) if model.has_matrix() => Ok(vec![robots::matrix(m)]),
            // The droid answers with north's yaw.
            Intent::CalibrateCompass if model.has_compass() => {
                Ok(vec![cmd::magnetometer_calibrate_to_north().into()])
            }
            Intent::Ir(ir) if model.has(Caps::IR) => Ok(robots::infrared(model, ir)
                .into_iter()
                .map(Command::from)
                .collect()),
            Intent::MainLight(rgb) => {
                if let Some(all) = robots::all_lights(model, *rgb) {
                    return Ok(vec![all]);
                }
                let mut out = Vec::new();
                for i in robots::main_light(model, *rgb) {
                    out.extend(self.lower(model, &i)?);
                }
                Ok(out)
            }
            _ => intent::lower_common(self, model, intent),
        }
    }

    fn tank(&self, left: i16, right: i16) -> Option<Command> {
        Some(robots::tank(left, right))
    }

    fn stream_caps(&self, model: Model) -> Option<StreamCaps> {
        let mut groups = SensorSet::of(&[
            SensorGroup::Attitude,
            SensorGroup::Accelerometer,
            SensorGroup::Gyro,
            SensorGroup::Locator,
            SensorGroup::Velocity,
        ]);
        if model.has_dome() {
            groups.insert(SensorGroup::HeadAngle);
        }
        Some(StreamCaps {
            groups,
            // The interval is in ms: every standard rate is exact.
            rates: &STANDARD_RATES,
            notifications_per_s: BLE_SENSOR_NOTIFICATIONS_PER_S,
        })
    }

    /// SOP, flags, DID, CID, SEQ, checksum and EOP around one f32 per value (escapes aside:
    /// they are rare in sensor floats).
    fn stream_sample_bytes(&self, sensors: SensorSet) -> usize {
        7 + 4 * stream_config(sensors, 1).value_count()
    }

    /// As the reference clients reconfigure: the mask with interval 0, the extended mask,
    /// then the mask again with the real interval (`droid-facts.md` §2). Off is all three
    /// with empty masks.
    fn streaming(&self, model: Model, plan: &StreamPlan) -> Vec<Command> {
        if model.streams_by_service() {
            // RVR streams through its streaming service, not masks: its fixed tokens at the
            // period asked for, or stopped.
            return if plan.is_on() {
                robots::rvr_streaming(plan.interval_ms)
            } else {
                robots::rvr_streaming_off()
            };
        }
        let mut s = if plan.is_on() {
            stream_config(plan.sensors, plan.interval_ms)
        } else {
            StreamingConfig::default()
        };
        if plan.is_on() && model.has_compass() {
            // BOLT's ambient light (extended bit 18, spherov2 `toy/bolt.py`).
            s.ext_mask |= 0x0004_0000;
        }
        vec![
            cmd::set_sensor_streaming_mask(0, 0, Mask(s.mask)).into(),
            cmd::set_extended_sensor_streaming_mask(Mask(s.ext_mask)).into(),
            cmd::set_sensor_streaming_mask(s.interval_ms, 0, Mask(s.mask)).into(),
        ]
    }

    /// Configure Collision Detection `[method, x_threshold, y_threshold, x_speed, y_speed,
    /// dead_time]` (spherov2's order, `droid-facts.md` §2), then its notification.
    fn collision_detection(&self, c: &CollisionConfig) -> Vec<Command> {
        let method = if c.enabled {
            CollisionMethod::Accelerometer
        } else {
            CollisionMethod::None
        };
        vec![
            cmd::configure_collision_detection(
                method,
                c.x_threshold,
                c.y_threshold,
                c.x_speed,
                c.y_speed,
                c.dead_time_units(),
            )
            .into(),
            cmd::enable_collision_detected_notify(c.enabled).into(),
        ]
    }

    fn read_drive(&self, c: &Command) -> Option<RecordedDrive> {
        let Command::V2(c) = c else { return None };
        match (c.did, c.cid, c.data.as_slice()) {
            (0x16, 0x07, [speed, h0, h1, flags]) => {
                let reverse = DriveFlags::from_bits_truncate(*flags).contains(DriveFlags::BACKWARD);
                let sent = Heading::wrapped(u16::from_be_bytes([*h0, *h1]) as f64);
                // A reverse drive carries the heading + 180° (see `drive`).
                let heading = if reverse { sent.reversed() } else { sent };
                Some(RecordedDrive {
                    speed: *speed,
                    heading,
                    reverse,
                    steer: None,
                })
            }
            _ => None,
        }
    }

    fn read_head(&self, c: &Command) -> Option<f32> {
        let Command::V2(c) = c else { return None };
        match (c.did, c.cid, c.data.as_slice()) {
            (0x17, 0x0F, [a, b, c, d]) => Some(f32::from_be_bytes([*a, *b, *c, *d])),
            _ => None,
        }
    }

    /// The 16-bit mask LED command: one value per set bit, ascending (`droid-facts.md` §2).
    /// R2: bits 0..2 front RGB (the main colour); BB-9E: 0..2 body RGB, 3 the aiming light.
    fn read_leds(&self, model: Model, c: &Command) -> Option<RecordedLeds> {
        let Command::V2(c) = c else { return None };
        if (c.did, c.cid) != (0x1A, 0x0E) || c.data.len() < 2 {
            return None;
        }
        let mask = u16::from_be_bytes([c.data[0], c.data[1]]);
        let mut values = c.data[2..].iter().copied();
        let mut by_bit = [None; 16];
        for (bit, slot) in by_bit.iter_mut().enumerate() {
            if mask & (1 << bit) != 0 {
                *slot = values.next();
            }
        }
        let main = match (by_bit[0], by_bit[1], by_bit[2]) {
            (Some(r), Some(g), Some(b)) => Some([r, g, b]),
            _ => None,
        };
        let back = if model.has_legs() { None } else { by_bit[3] };
        (main.is_some() || back.is_some()).then_some(RecordedLeds { main, back })
    }
}

/// The masks of `sensors` at `interval_ms`.
fn stream_config(sensors: SensorSet, interval_ms: u16) -> StreamingConfig {
    use crate::protocol::v2::sensor::mask;
    let mut s = StreamingConfig {
        interval_ms,
        ..StreamingConfig::default()
    };
    for g in sensors.iter() {
        match g {
            SensorGroup::Attitude => s.mask |= mask::ATTITUDE,
            SensorGroup::Accelerometer => s.mask |= mask::ACCELEROMETER,
            SensorGroup::Locator => s.mask |= mask::LOCATOR,
            SensorGroup::Velocity => s.mask |= mask::VELOCITY,
            SensorGroup::Gyro => s.ext_mask |= mask::EXT_GYRO,
            SensorGroup::HeadAngle => s.ext_mask |= mask::EXT_HEAD_ANGLE,
        }
    }
    s
}

#[cfg(test)]
mod service_tests {
    use super::*;
    use crate::family::Codec;
    use crate::protocol::v2::stream::{self, ServiceConfig};
    use crate::protocol::v2::types::{StreamSlots, StreamWidth};
    use targets::Processor;

    /// Issue 30 point 7: RVR's streaming-service data in the log are named by what this
    /// connection configured, not `token=1 data=[…]`.
    #[test]
    fn streaming_service_data_are_explained_by_what_was_configured() {
        let mut codec = V2Codec::for_model(Model::Rvr);
        let configure = cmd::configure_streaming_service(
            2,
            StreamSlots(vec![(6, StreamWidth::Bits32), (7, StreamWidth::Bits32)]),
        )
        .to(Processor::Secondary);
        let sensor = v2::Device::parse("sensor").expect("sensor device");
        let mut cfg = ServiceConfig::default();
        cfg.snoop(&configure);
        let slot = cfg
            .slot(Some(Processor::Secondary), 2)
            .expect("slot")
            .clone();
        let data = stream::encode(&slot, &[("locator_x", 120.0), ("velocity_y", -30.0)]);
        let mut p = v2::Packet::notification(sensor, 0x3D, data);
        p.sid = Some(Processor::Secondary.target_id());
        p.flags.insert(Flags::HAS_SOURCE_ID);
        let packet = Packet::V2(p);
        let before = codec.explain(&packet, None);
        let _ = codec.encode(&Command::V2(configure), 1, true);
        let after = codec.explain(&packet, None);
        let names = |e: &Explained| -> Vec<&'static str> {
            e.fields.iter().flatten().map(|(n, _)| *n).collect()
        };
        assert!(!names(&before).contains(&"locator_x"), "{before:?}");
        assert!(names(&after).contains(&"locator_x"), "{after:?}");
        assert!(names(&after).contains(&"velocity_y"), "{after:?}");
    }
}
