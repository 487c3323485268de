//! Core and System Info: versions, names, config blocks, event logs.

use super::*;

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
}
