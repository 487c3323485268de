//! The notifications: what a droid sends unasked (SEQ 0xFF).

use super::*;

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
        // BOLT's matrix (spherov2 `commands/io.py`): scrolling text done or looping, and an
        // animation played to its end.
        0x3C text_scrolling "Text Scrolling" (reason: TextScrollReason);
        0x3F compressed_frame_player_animation_complete "Compressed Frame Player Animation Complete" (animation_id: u8);
    }
    ApiAndShell {
        0x03 send_string_to_console "Send String To Console" (text: Text);
    }
}
