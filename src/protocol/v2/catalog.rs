//! The command and notification catalogue: the single source of truth for names, ids and
//! payload schemas. The CLI (`packet encode`, `packet decode`), the packet log and the
//! simulator's length checks all read it; the typed constructors in [`cmd`] are generated from
//! the same table, so the two can never disagree.
//!
//! Sources: `r2d2-v2-protocol.md` §4 for ids and sizes, corrected by `droid-facts.md` §2
//! (head position is degrees, collision is 18 bytes). Where the seed gives only a size
//! ("2 bytes"), field names and types follow spherov2.py's command modules; names marked
//! there as unknown are kept generic (`data`).

use super::device::Device;
use super::packet::Packet;
use crate::protocol::wire::*;
use crate::units::{HeadAngle, Heading};
use std::collections::HashMap;
use std::sync::LazyLock;

/// A command ready to be framed: device, command id and payload.
#[derive(Debug, Clone, PartialEq, Eq, Hash)]
pub struct Command {
    pub did: u8,
    pub cid: u8,
    pub data: Vec<u8>,
}

impl Command {
    /// Frame with the default flags (0x0A) and the given SEQ.
    pub fn to_packet(&self, seq: u8) -> Packet {
        Packet::command(self.did, self.cid, seq, self.data.clone())
    }

    /// The catalogue entry for this command, if any.
    pub fn def(&self) -> Option<&'static CommandDef> {
        lookup(self.did, self.cid)
    }
}

pub use crate::protocol::schema::{
    FieldDef, Schema, decode_fields, length_ok, min_len, minimal_payload,
};

pub use crate::protocol::table::CommandDef;
use crate::protocol::table::{CommandTable, RawCommand};

/// One notification of the catalogue.
#[derive(Debug)]
pub struct NotificationDef {
    pub name: String,
    pub spec_name: &'static str,
    pub device: Device,
    pub cid: u8,
    pub fields: Schema,
}

struct RawNotification {
    device: Device,
    cid: u8,
    fn_name: &'static str,
    spec_name: &'static str,
    fields: Schema,
}

macro_rules! catalogue {
    ($( $dev:ident { $( $cid:literal $fname:ident $spec:literal ( $($p:ident : $pty:ty $(= $def:literal)?),* ) -> ( $($r:ident : $rty:ty),* ) ; )* } )*) => {
        /// Typed constructors, one per catalogue command: typed parameters in, payload out.
        pub mod cmd {
            #[allow(unused_imports)]
            use super::*;
            $( $(
                #[doc = concat!("`", $spec, "` (", stringify!($dev), ", CID ", stringify!($cid), ").")]
                pub fn $fname($($p: $pty),*) -> Command {
                    #[allow(unused_mut)]
                    let mut data = Vec::new();
                    $( Wire::put(&$p, &mut data); )*
                    Command { did: Device::$dev.id(), cid: $cid, data }
                }
            )* )*
        }

        static RAW_COMMANDS: &[RawCommand] = &[ $( $( RawCommand {
            did: Device::$dev.id(),
            cid: $cid,
            fn_name: stringify!($fname),
            spec_name: $spec,
            params: &[ $( FieldDef::of::<$pty>(stringify!($p)) $(.with_default($def))? ),* ],
            response: &[ $( FieldDef::of::<$rty>(stringify!($r)) ),* ],
        }, )* )* ];
    };
}

macro_rules! notifications {
    ($( $dev:ident { $( $cid:literal $fname:ident $spec:literal ( $($f:ident : $fty:ty),* ) ; )* } )*) => {
        static RAW_NOTIFICATIONS: &[RawNotification] = &[ $( $( RawNotification {
            device: Device::$dev,
            cid: $cid,
            fn_name: stringify!($fname),
            spec_name: $spec,
            fields: &[ $( FieldDef::of::<$fty>(stringify!($f)) ),* ],
        }, )* )* ];
    };
}

catalogue! {
    Core {
        0x01 ping "Ping" () -> ();
        0x02 get_versions "Get Versions" () -> (record_version: u8, model_number: u8, hardware_version: u8,
            main_app_major: u8, main_app_minor: u8, bootloader_version: u8, orb_basic_version: u8, overlay_version: u8);
        0x10 set_bluetooth_name "Set Bluetooth Name" (name: Text) -> ();
        0x11 get_bluetooth_info "Get Bluetooth Info" () -> (name_and_address: Text);
        0x20 get_power_state "Get Power State" () -> (record_version: u8, state: PowerState, voltage: CentiVolts,
            number_of_charges: u16, time_since_last_charge: u16);
        0x21 enable_battery_changed_notify "Enable Battery Changed Notify" (enable: bool = "true") -> ();
        // Same spec name as Power/Sleep: the Core one is prefixed to keep names unique.
        0x22 core_sleep "Sleep" (interval: u16 = "0", unk: u8 = "0", unk2: u16 = "0") -> ();
        0x25 set_inactivity_timeout "Set Inactivity Timeout" (timeout: u16) -> ();
        0x26 core_get_charger_state "Get Charger State" () -> (state: CoreChargerState);
        0x27 get_factory_config_block_crc "Get Factory Config Block CRC" () -> (crc: Mask<4>);
        0x30 jump_to_bootloader "Jump to Bootloader" () -> ();
    }
    SystemInfo {
        0x00 get_main_app_version "Get Main App Version" () -> (major: u16, minor: u16, revision: u16);
        0x01 get_bootloader_version "Get Bootloader Version" () -> (major: u16, minor: u16, revision: u16);
        0x03 get_board_revision "Get Board Revision" () -> (revision: u8);
        0x06 get_mac_address "Get MAC Address" () -> (address: Bytes);
        0x12 get_model_number "Get Model Number" () -> (model: Bytes);
        0x13 get_stats_id "Get Stats ID" () -> (stats_id: Bytes);
        0x17 get_secondary_main_app_version "Get Secondary Main App Version" () -> ();
        0x1F get_processor_name "Get Processor Name" () -> (name: Text);
        0x20 get_boot_reason "Get Boot Reason" () -> (reason: BootReason);
        0x21 get_last_error_info "Get Last Error Info" () -> (file_name: FixedText<32>, line_number: u16, data: [u8; 12]);
        0x24 get_secondary_mcu_bootloader_version "Get Secondary MCU Bootloader Version" () -> ();
        0x28 get_three_character_sku "Get Three Character SKU" () -> (sku: Text);
        0x2B write_config_block "Write Config Block" () -> ();
        0x2C get_config_block "Get Config Block" () -> (metadata_version: u32, config_block_version: u32, application_data: Bytes);
        0x2D set_config_block "Set Config Block" (metadata_version: u32, config_block_version: u32, application_data: Bytes) -> ();
        0x2E erase_config_block "Erase Config Block" (value: u32) -> ();
        0x30 get_swd_locking_status "Get SWD Locking Status" () -> (locked: bool);
        0x33 get_manufacturing_date "Get Manufacturing Date" () -> (year: u16, month: u8, day: u8);
        0x38 get_sku "Get SKU" () -> (sku: Text);
        0x39 get_core_up_time "Get Core Up Time" () -> (uptime_ms: u32);
        0x3A get_event_log_status "Get Event Log Status" () -> (word_0: u32, word_1: u32, word_2: u32);
        0x3B get_event_log_data "Get Event Log Data" (offset: u32, size: u32) -> (data: Bytes);
        0x3C clear_event_log "Clear Event Log" () -> ();
        0x3D enable_sos_message_notify "Enable SOS Message Notify" (enable: bool = "true") -> ();
        0x3F get_sos_message "Get SOS Message" () -> ();
        0x44 clear_sos_message "Clear SOS Message" () -> ();
    }
    Power {
        0x00 enter_deep_sleep "Enter Deep Sleep" (option: u8 = "0") -> ();
        0x01 sleep "Sleep" () -> ();
        0x03 get_battery_voltage "Get Battery Voltage" () -> (voltage: CentiVolts);
        0x04 get_battery_state "Get Battery State" () -> (state: BatteryState);
        0x05 enable_battery_state_changed_notify "Enable Battery State Changed Notify" (enable: bool = "true") -> ();
        0x0C force_battery_refresh "Force Battery Refresh" () -> ();
        0x0D wake "Wake" () -> ();
        0x10 get_battery_percentage "Get Battery Percentage" () -> (percent: u8);
        0x17 get_battery_voltage_state "Get Battery Voltage State" () -> (state: BatteryVoltageState);
        0x1B enable_battery_voltage_state_change_notify "Enable Battery Voltage State Change Notify" (enable: bool = "true") -> ();
        0x1F get_charger_state "Get Charger State" () -> (state: ChargerState);
        0x20 enable_charger_state_changed_notify "Enable Charger State Changed Notify" (enable: bool = "true") -> ();
        0x22 get_battery_adc_reading "Get Battery ADC Reading" () -> (reading: u8);
        0x23 set_battery_calibration "Set Battery Calibration" (slope: u8, intercept: u8) -> ();
        0x24 get_battery_calibration "Get Battery Calibration" () -> (calibration: u8);
        0x25 get_battery_voltage_in_volts "Get Battery Voltage In Volts" (reading_type: VoltageReadingType) -> (volts: f32);
        0x26 get_battery_voltage_state_thresholds "Get Battery Voltage State Thresholds" () -> (critical: f32, low: f32, hysteresis: f32);
        0x27 get_current_sense_amplifier_current "Get Current Sense Amplifier Current" (amplifier: AmplifierId) -> (amps: f32);
        0x28 get_efuse_fault_status "Get EFuse Fault Status" (efuse: u8) -> (status: u8);
        0x2A enable_efuse "Enable EFuse" (efuse: u8) -> ();
    }
    Drive {
        0x01 set_raw_motors "Set Raw Motors" (left_mode: RawMotorMode, left_speed: u8, right_mode: RawMotorMode, right_speed: u8) -> ();
        0x06 reset_yaw "Reset Yaw" () -> ();
        0x07 drive_with_heading "Drive With Heading" (speed: u8, heading: Heading, flags: DriveFlags = "0") -> ();
        0x0B generic_raw_motor "Generic Raw Motor" (index: MotorIndex, mode: RawMotorMode, speed: Bytes) -> ();
        0x0C set_stabilization "Set Stabilization" (index: StabilizationIndex) -> ();
        0x0E set_control_system_type "Set Control System Type" (control_type: u8, controller: u8) -> ();
        0x0F set_pitch_torque_modification "Set Pitch Torque Modification" (value: u8) -> ();
        0x20 set_component_parameters "Set Component Parameters" (component: u8, parameter: u8, values: F32List) -> ();
        0x21 get_component_parameters "Get Component Parameters" (component: u8, parameter: u8) -> (values: F32List);
        0x22 set_custom_control_system_timeout "Set Custom Control System Timeout" (timeout_ms: u16) -> ();
        0x25 enable_motor_stall_notify "Enable Motor Stall Notify" (enable: bool = "true") -> ();
        0x27 enable_motor_fault_notify "Enable Motor Fault Notify" (enable: bool = "true") -> ();
        0x29 get_motor_fault_state "Get Motor Fault State" () -> (fault: bool);
    }
    Animatronic {
        0x05 play_animation "Play Animation" (id: u16) -> ();
        0x0D perform_leg_action "Perform Leg Action" (action: LegAction) -> ();
        // Degrees, not radians (droid-facts.md §2 corrects the seed).
        0x0F set_head_position "Set Head Position" (degrees: HeadAngle) -> ();
        0x14 get_head_position "Get Head Position" () -> (degrees: f32);
        0x15 set_leg_position "Set Leg Position" (position: f32) -> ();
        0x16 get_leg_position "Get Leg Position" () -> (position: f32);
        0x25 get_leg_action "Get Leg Action" () -> (state: LegState);
        0x2A enable_leg_action_notify "Enable Leg Action Notify" (enable: bool = "true") -> ();
        0x2B stop_animation "Stop Animation" () -> ();
        0x2C enable_idle_animations "Enable Idle Animations" (enable: bool = "true") -> ();
        0x2D enable_trophy_mode "Enable Trophy Mode" (enable: bool = "true") -> ();
        0x2E get_trophy_mode_enabled "Get Trophy Mode Enabled" () -> (enabled: bool);
        0x39 enable_head_reset_to_zero_notify "Enable Head Reset to Zero Notify" (enable: bool = "true") -> ();
    }
    Sensor {
        0x00 set_sensor_streaming_mask "Set Sensor Streaming Mask" (interval_ms: u16, count: u8 = "0", mask: Mask<4>) -> ();
        0x01 get_sensor_streaming_mask "Get Sensor Streaming Mask" () -> (interval_ms: u16, count: u8, mask: Mask<4>);
        0x0C set_extended_sensor_streaming_mask "Set Extended Sensor Streaming Mask" (mask: Mask<4>) -> ();
        0x0D get_extended_sensor_streaming_mask "Get Extended Sensor Streaming Mask" () -> (mask: Mask<4>);
        0x0F enable_gyro_max_notify "Enable Gyro Max Notify" (enable: bool = "true") -> ();
        // dead_time is in 10 ms units (droid-facts.md §2).
        0x11 configure_collision_detection "Configure Collision Detection" (method: CollisionMethod = "1", x_threshold: u8 = "90",
            y_threshold: u8 = "130", x_speed: u8 = "90", y_speed: u8 = "130", dead_time: u8 = "1") -> ();
        0x13 reset_locator_x_and_y "Reset Locator X and Y" () -> ();
        0x14 enable_collision_detected_notify "Enable Collision Detected Notify" (enable: bool = "true") -> ();
        0x17 set_locator_flags "Set Locator Flags" (flags: bool = "false") -> ();
        0x18 set_accelerometer_activity_threshold "Set Accelerometer Activity Threshold" (threshold: f32) -> ();
        0x19 enable_accelerometer_activity_notify "Enable Accelerometer Activity Notify" (enable: bool = "true") -> ();
        0x1B set_gyro_activity_threshold "Set Gyro Activity Threshold" (threshold: f32) -> ();
        0x1C enable_gyro_activity_notify "Enable Gyro Activity Notify" (enable: bool = "true") -> ();
        0x22 get_bot_to_bot_infrared_readings "Get Bot To Bot Infrared Readings" () -> (readings: [u8; 4]);
        0x23 get_rgbc_sensor_values "Get RGBC Sensor Values" () -> (red: u16, green: u16, blue: u16, clear: u16);
        0x25 magnetometer_calibrate_to_north "Magnetometer Calibrate To North" () -> ();
        0x27 start_robot_to_robot_ir_broadcasting "Start Robot To Robot IR Broadcasting" (far_code: u8, near_code: u8) -> ();
        0x28 start_robot_to_robot_ir_following "Start Robot To Robot IR Following" (far_code: u8, near_code: u8) -> ();
        0x29 stop_robot_to_robot_ir_broadcasting "Stop Robot To Robot IR Broadcasting" () -> ();
        0x2A send_robot_to_robot_ir_message "Send Robot To Robot IR Message" (data: [u8; 5]) -> ();
        0x2B listen_for_robot_to_robot_ir_message "Listen For Robot To Robot IR Message" (data: [u8; 2]) -> ();
        0x30 get_ambient_light_sensor_value "Get Ambient Light Sensor Value" () -> (lux: f32);
        0x32 stop_robot_to_robot_ir_following "Stop Robot To Robot IR Following" () -> ();
        0x33 start_robot_to_robot_ir_evading "Start Robot To Robot IR Evading" (far_code: u8, near_code: u8) -> ();
        0x34 stop_robot_to_robot_ir_evading "Stop Robot To Robot IR Evading" () -> ();
        0x35 enable_color_detection_notify "Enable Color Detection Notify" (enable: bool, interval_ms: u16, confidence_threshold: u8) -> ();
        0x37 get_current_detected_color_reading "Get Current Detected Color Reading" () -> (data: Bytes);
        0x38 enable_color_detection "Enable Color Detection" (enable: bool = "true") -> ();
        0x39 configure_streaming_service "Configure Streaming Service" (config: Bytes) -> ();
        0x3A start_streaming_service "Start Streaming Service" (period_ms: u16) -> ();
        0x3B stop_streaming_service "Stop Streaming Service" () -> ();
        0x3C clear_streaming_service "Clear Streaming Service" () -> ();
        0x3E enable_robot_ir_message_notify "Enable Robot IR Message Notify" (enable: bool = "true") -> ();
        0x3F send_infrared_message "Send Infrared Message" (data: [u8; 5]) -> ();
        0x41 enable_motor_current_notify "Enable Motor Current Notify" (enable: bool = "true") -> ();
        0x42 get_motor_temperature "Get Motor Temperature" (motor: u8) -> (case_temperature: f32, winding_temperature: f32);
        0x47 configure_sensitivity_based_collision "Configure Sensitivity Based Collision" (data: [u8; 4]) -> ();
        0x48 enable_sensitivity_based_collision_notify "Enable Sensitivity Based Collision Notify" (enable: bool = "true") -> ();
        0x4B get_motor_thermal_protection_status "Get Motor Thermal Protection Status" () -> (data: [u8; 10]);
        0x4C enable_motor_thermal_protection_notify "Enable Motor Thermal Protection Notify" (enable: bool = "true") -> ();
    }
    Io {
        0x04 set_led "Set LED" (data: [u8; 5]) -> ();
        0x07 play_audio_file "Play Audio File" (sound: u16, mode: AudioMode = "0") -> ();
        0x08 set_audio_volume "Set Audio Volume" (volume: u8) -> ();
        0x09 get_audio_volume "Get Audio Volume" () -> (volume: u8);
        0x0A stop_all_audio "Stop All Audio" () -> ();
        // One value byte per set mask bit, ascending bit order (droid-facts.md §2).
        0x0E set_all_leds_with_16_bit_mask "Set All LEDs With 16-bit Mask" (mask: Mask<2>, values: Bytes) -> ();
        0x19 start_idle_led_animation "Start Idle LED Animation" () -> ();
        0x1A set_all_leds_with_32_bit_mask "Set All LEDs With 32-bit Mask" (mask: Mask<4>, values: Bytes) -> ();
        0x1C set_all_leds_with_8_bit_mask "Set All LEDs With 8-bit Mask" (mask: Mask<1>, values: Bytes) -> ();
        0x1D enable_color_tap_notify "Enable Color Tap Notify" (enable: bool = "true") -> ();
    }
}

notifications! {
    SystemInfo {
        0x18 secondary_main_app_version "Secondary Main App Version" (major: u16, minor: u16, revision: u16);
        0x25 secondary_mcu_bootloader_version "Secondary MCU Bootloader Version" (major: u16, minor: u16, revision: u16);
        0x3E sos_message "SOS Message" (message: u8);
    }
    Power {
        // 0x06, 0x19, 0x1A, 0x1C and 0x21 are from droid-facts.md §2 (not in the seed).
        0x06 battery_state_changed "Battery State Changed" (state: BatteryVoltageAndState);
        0x19 will_sleep "Will Sleep" ();
        0x1A did_sleep "Did Sleep" ();
        0x1C battery_voltage_state_changed "Battery Voltage State Changed" (state: BatteryVoltageState);
        0x21 charger_state_changed "Charger State Changed" (state: u8);
        0x29 efuse_fault_occurred "EFuse Fault Occurred" (efuse: u8);
    }
    Drive {
        0x26 motor_stall "Motor Stall" (motor: u8, stalled: bool);
        0x28 motor_fault "Motor Fault" (fault: bool);
    }
    Animatronic {
        // The payloads of these two are undocumented; they are kept as raw bytes.
        0x11 play_animation_complete "Play Animation Complete" (data: Bytes);
        0x26 leg_action_complete "Leg Action Complete" (data: Bytes);
        0x3A head_reset_to_zero "Head Reset To Zero" ();
    }
    Sensor {
        // Decoded into named values with the masks in effect by `sensor::decode_sample`.
        0x02 sensor_streaming_data "Sensor Streaming Data" (values: F32List);
        0x10 gyro_max "Gyro Max" (flags: u8);
        // 18 bytes, not the seed's 17 (droid-facts.md §2, §3).
        0x12 collision_detected "Collision Detected" (accel_x: AccelRaw, accel_y: AccelRaw, accel_z: AccelRaw,
            axis: CollisionAxis, power_x: i16, power_y: i16, power_z: i16, speed: u8, time_ms: u32);
        0x1A accelerometer_activity "Accelerometer Activity" ();
        0x1D gyro_activity "Gyro Activity" ();
        0x26 magnetometer_north_yaw "Magnetometer North Yaw" (yaw: u16);
        0x2C robot_to_robot_ir_message "Robot To Robot IR Message" (code: u8);
        0x36 color_detection "Color Detection" (red: u8, green: u8, blue: u8, index: u8, confidence: u8);
        0x3D streaming_service_data "Streaming Service Data" (token: u8, data: Bytes);
        0x40 motor_current "Motor Current" (data: [u8; 16]);
        0x49 sensitivity_collision "Sensitivity Collision" (data: [u8; 4]);
        0x4D motor_thermal_protection "Motor Thermal Protection" (data: [u8; 10]);
    }
    Io {
        0x1E color_tap "Color Tap" (data: u8);
    }
}

/// The notifications, indexed by id.
struct Notifications {
    all: Vec<NotificationDef>,
    by_id: HashMap<(u8, u8), usize>,
}

static COMMANDS: LazyLock<CommandTable> = LazyLock::new(|| CommandTable::new(RAW_COMMANDS));

static NOTIFICATIONS: LazyLock<Notifications> = LazyLock::new(|| {
    let all: Vec<NotificationDef> = RAW_NOTIFICATIONS
        .iter()
        .map(|r| NotificationDef {
            name: r.fn_name.replace('_', "-"),
            spec_name: r.spec_name,
            device: r.device,
            cid: r.cid,
            fields: r.fields,
        })
        .collect();
    let by_id = all
        .iter()
        .enumerate()
        .map(|(i, n)| ((n.device.id(), n.cid), i))
        .collect();
    Notifications { all, by_id }
});

/// Every command, in table order.
pub fn commands() -> &'static [CommandDef] {
    COMMANDS.commands()
}

/// Every notification, in table order.
pub fn notifications() -> &'static [NotificationDef] {
    &NOTIFICATIONS.all
}

/// The command with this DID/CID.
pub fn lookup(did: u8, cid: u8) -> Option<&'static CommandDef> {
    COMMANDS.lookup(did, cid)
}

/// The command with this kebab-case name.
pub fn by_name(name: &str) -> Option<&'static CommandDef> {
    COMMANDS.by_name(name)
}

/// The notification with this DID/CID.
pub fn notification(did: u8, cid: u8) -> Option<&'static NotificationDef> {
    NOTIFICATIONS
        .by_id
        .get(&(did, cid))
        .map(|&i| &NOTIFICATIONS.all[i])
}

/// Command names closest to `name`, for "did you mean" hints.
pub fn suggestions(name: &str) -> Vec<&'static str> {
    COMMANDS.suggestions(name)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn kebab(spec: &str) -> String {
        spec.to_ascii_lowercase().replace(' ', "-")
    }

    #[test]
    fn names_derive_from_spec_names_and_are_unique() {
        let mut seen = std::collections::HashSet::new();
        for c in commands() {
            let derived = kebab(c.spec_name);
            assert!(
                c.name == derived || c.name == format!("core-{derived}"),
                "{} vs {}",
                c.name,
                c.spec_name
            );
            assert!(seen.insert(c.name.clone()), "duplicate {}", c.name);
            assert!(seen.len() <= commands().len());
        }
        let ids: std::collections::HashSet<_> = commands().iter().map(|c| (c.did, c.cid)).collect();
        assert_eq!(ids.len(), commands().len(), "duplicate DID/CID");
        for n in notifications() {
            assert_eq!(n.name, kebab(n.spec_name));
        }
    }

    #[test]
    fn catalogue_covers_every_seed_table_row() {
        // Counts of rows in r2d2-v2-protocol.md §4.2–§4.8.
        let count = |d: Device| {
            commands()
                .iter()
                .filter(|c| Device::from_id(c.did) == Some(d))
                .count()
        };
        assert_eq!(count(Device::Core), 11);
        assert_eq!(count(Device::SystemInfo), 26);
        assert_eq!(count(Device::Power), 20);
        assert_eq!(count(Device::Drive), 13);
        assert_eq!(count(Device::Animatronic), 13);
        assert_eq!(count(Device::Sensor), 40);
        assert_eq!(count(Device::Io), 10);
    }

    #[test]
    fn issue_examples_encode() {
        let c = by_name("drive-with-heading").unwrap();
        let given = |pairs: &[(&str, &str)]| -> Vec<(String, String)> {
            pairs
                .iter()
                .map(|(k, v)| (k.to_string(), v.to_string()))
                .collect()
        };
        assert_eq!(
            c.encode_params(&given(&[
                ("speed", "100"),
                ("heading", "180"),
                ("flags", "0")
            ])),
            Ok(vec![100, 0, 180, 0])
        );
        let err = c
            .encode_params(&given(&[
                ("speed", "100"),
                ("heading", "360"),
                ("flags", "0"),
            ]))
            .unwrap_err();
        assert!(
            err.contains("--heading") && err.contains("0..=359"),
            "{err}"
        );
        let err = c.encode_params(&given(&[("speed", "100")])).unwrap_err();
        assert!(err.contains("needs --heading"), "{err}");
        // Flags default to none (issue 8), so speed and heading are enough.
        assert_eq!(
            c.encode_params(&given(&[("speed", "100"), ("heading", "180")])),
            Ok(vec![100, 0, 180, 0])
        );
        // Collision detection defaults to the common reference-client values.
        assert_eq!(
            by_name("configure-collision-detection")
                .unwrap()
                .encode_params(&[]),
            Ok(vec![1, 90, 130, 90, 130, 1])
        );
        let err = by_name("wake")
            .unwrap()
            .encode_params(&given(&[("x", "1")]))
            .unwrap_err();
        assert!(err.contains("takes no parameters"));
    }

    #[test]
    fn length_rules() {
        let drive = by_name("drive-with-heading").unwrap();
        assert!(length_ok(drive.params, 4));
        assert!(!length_ok(drive.params, 3));
        assert!(!length_ok(drive.params, 5));
        let leds = by_name("set-all-leds-with-16-bit-mask").unwrap();
        assert!(length_ok(leds.params, 3));
        assert!(!length_ok(leds.params, 1));
    }

    #[test]
    fn suggestions_find_close_names() {
        assert!(suggestions("drive-heading").contains(&"drive-with-heading"));
    }
}
