//! Drive and Animatronic: driving, raw motors, control systems, R2's dome and legs.

use super::*;

catalogue! {
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
}
