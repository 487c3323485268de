//! The devices of the newer robots (BOLT, Mini, RVR) that R2-D2's seed tables leave out:
//! API and Shell, System Mode, Connection, Firmware and Factory Test. Ids and layouts are
//! spherov2.py's `commands/{api_and_shell,system_mode,connection,firmware,factory_test}.py`;
//! where spherov2 names a field only `s` or `data`, it stays raw bytes here.

use super::*;

catalogue! {
    ApiAndShell {
        // spherov2 calls it `ping`; Sphero's SDK calls API & Shell 0x00 "Echo" (the data
        // comes back), which keeps it apart from Core's Ping.
        0x00 echo "Echo" (data: Bytes) -> (data: Bytes);
        0x01 get_api_protocol_version "Get API Protocol Version" () -> (major: u8, minor: u8);
        0x02 send_command_to_shell "Send Command To Shell" (command: Text) -> ();
        0x05 get_supported_dids "Get Supported DIDs" () -> (dids: Bytes);
        0x06 get_supported_cids "Get Supported CIDs" (did: u8) -> (cids: Bytes);
    }
    SystemMode {
        0x29 enable_desktoy_mode "Enable Desktoy Mode" (enable: bool = "true") -> ();
        0x2B get_out_of_box_state "Get Out Of Box State" () -> (enabled: bool);
        0x2C enable_out_of_box_state "Enable Out Of Box State" (enable: bool = "true") -> ();
    }
    Connection {
        // Same spec name as Core's: the Connection one is prefixed to keep names unique.
        0x03 connection_set_bluetooth_name "Set Bluetooth Name" (name: Text) -> ();
        0x04 get_bluetooth_name "Get Bluetooth Name" () -> (name: Text);
        0x05 get_bluetooth_advertising_name "Get Bluetooth Advertising Name" () -> (name: Text);
    }
    Firmware {
        0x0D get_pending_update_flags "Get Pending Update Flags" () -> (flags: Bytes);
        0x15 get_current_application_id "Get Current Application ID" () -> (application: u8);
        0x16 get_all_updatable_processors "Get All Updatable Processors" () -> (data: Bytes);
        0x18 get_version_for_updatable_processors "Get Version For Updatable Processors" () -> (data: Bytes);
        0x1A set_pending_update_for_processors "Set Pending Update For Processors" (data: Bytes) -> (reset_strategy: u8);
        0x1B get_pending_update_for_processors "Get Pending Update For Processors" () -> (data: Bytes);
        0x1C reset_with_parameters "Reset With Parameters" (reset_strategy: u8) -> ();
        0x26 clear_pending_update_processors "Clear Pending Update Processors" (data: Bytes) -> ();
    }
    FactoryTest {
        0x13 get_factory_mode_challenge "Get Factory Mode Challenge" () -> (challenge: u32);
        0x14 enter_factory_mode "Enter Factory Mode" (challenge: u32) -> ();
        0x15 exit_factory_mode "Exit Factory Mode" () -> ();
        0x27 get_chassis_id "Get Chassis ID" () -> (chassis_id: Bytes);
        0x31 enable_extended_life_test "Enable Extended Life Test" (enable: bool = "true") -> ();
        0x34 get_factory_mode_status "Get Factory Mode Status" () -> (enabled: bool);
    }
}
