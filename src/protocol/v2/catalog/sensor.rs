//! Sensor: mask streaming, the streaming service, collisions, compass, light, colour, IR.

use super::*;

catalogue! {
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
        // A token (slot) and its sensors: id u16 and value width each (spherov2's
        // `controls/v2.py` StreamingControl).
        0x39 configure_streaming_service "Configure Streaming Service" (token: u8, slots: StreamSlots) -> ();
        0x3A start_streaming_service "Start Streaming Service" (period_ms: u16) -> ();
        0x3B stop_streaming_service "Stop Streaming Service" () -> ();
        0x3C clear_streaming_service "Clear Streaming Service" () -> ();
        0x3E enable_robot_ir_message_notify "Enable Robot IR Message Notify" (enable: bool = "true") -> ();
        0x3F send_infrared_message "Send Infrared Message" (data: [u8; 5]) -> ();
        0x41 enable_motor_current_notify "Enable Motor Current Notify" (enable: bool = "true") -> ();
        0x42 get_motor_temperature "Get Motor Temperature" (motor: u8) -> (case_temperature: f32, winding_temperature: f32);
        // spherov2: [method, level, u16]; the u16's meaning is not given (named `i` there).
        0x47 configure_sensitivity_based_collision "Configure Sensitivity Based Collision" (method: u8, level: u8, value: u16) -> ();
        0x48 enable_sensitivity_based_collision_notify "Enable Sensitivity Based Collision Notify" (enable: bool = "true") -> ();
        0x4B get_motor_thermal_protection_status "Get Motor Thermal Protection Status" () -> (data: [u8; 10]);
        0x4C enable_motor_thermal_protection_notify "Enable Motor Thermal Protection Notify" (enable: bool = "true") -> ();
    }
}
