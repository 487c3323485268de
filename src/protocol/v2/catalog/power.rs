//! Power: sleep and wake, battery and charger, eFuses.

use super::*;

catalogue! {
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
}
