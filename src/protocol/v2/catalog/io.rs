//! IO: audio, LEDs, and BOLT's LED matrix (the "compressed frame player").

use super::*;

catalogue! {
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
        // BOLT's 8×8 matrix and RVR's palette commands: spherov2.py `commands/io.py` (no seed
        // spec; `droid-facts.md` §6). Coordinates are 0..=7, x to the right, y down.
        0x2D set_compressed_frame_player_pixel "Set Compressed Frame Player Pixel" (x: u8, y: u8, red: u8, green: u8, blue: u8) -> ();
        0x2E set_compressed_frame_player "Set Compressed Frame Player" (data: Bytes) -> ();
        0x2F set_compressed_frame_player_one_color "Set Compressed Frame Player One Color" (red: u8, green: u8, blue: u8) -> ();
        0x30 save_compressed_frame_player_64_bit_frame "Save Compressed Frame Player 64 Bit Frame" (frame_index: u16, frame: Bytes) -> ();
        0x31 save_compressed_frame_player_animation "Save Compressed Frame Player Animation" (animation_id: u8, fps: u8, fade: bool,
            palette: Palette, frames: FrameList) -> ();
        0x32 play_compressed_frame_player_animation "Play Compressed Frame Player Animation" (animation_id: u8) -> ();
        0x33 play_compressed_frame_player_frame "Play Compressed Frame Player Frame" (frame_index: u16) -> ();
        0x34 get_compressed_frame_player_list_of_frames "Get Compressed Frame Player List Of Frames" () -> (frames: U16List);
        0x35 delete_all_compressed_frame_player_animations_and_frames "Delete All Compressed Frame Player Animations And Frames" () -> ();
        0x36 pause_compressed_frame_player_animation "Pause Compressed Frame Player Animation" () -> ();
        0x37 resume_compressed_frame_player_animation "Resume Compressed Frame Player Animation" () -> ();
        0x38 reset_compressed_frame_player_animation "Reset Compressed Frame Player Animation" () -> ();
        0x39 override_compressed_frame_player_animation_global_settings "Override Compressed Frame Player Animation Global Settings"
            (fps: u8, fade: FadeOverride) -> ();
        0x3A set_compressed_frame_player_frame_rotation "Set Compressed Frame Player Frame Rotation" (rotation: FrameRotation) -> ();
        // spherov2 keeps the speed below 0x1F and the text to 25 characters, NUL-terminated.
        0x3B set_compressed_frame_player_text_scrolling "Set Compressed Frame Player Text Scrolling" (red: u8, green: u8, blue: u8,
            speed: u8 = "7", repeat: bool = "false", text: ScrollText) -> ();
        0x3D draw_compressed_frame_player_line "Draw Compressed Frame Player Line" (x1: u8, y1: u8, x2: u8, y2: u8,
            red: u8, green: u8, blue: u8) -> ();
        0x3E draw_compressed_frame_player_fill "Draw Compressed Frame Player Fill" (x1: u8, y1: u8, x2: u8, y2: u8,
            red: u8, green: u8, blue: u8) -> ();
        // spherov2 sends the animation id, then big-endian u16s (`i` and `i_arr`, unnamed).
        0x40 assign_compressed_frame_player_frames_to_animation "Assign Compressed Frame Player Frames To Animation"
            (animation_id: u8, frames: U16List) -> ();
        // spherov2 names these fields only s, s2, z, s3, s_arr and i: kept as raw bytes after the three it explains.
        0x41 save_compressed_frame_player_animation_without_frames "Save Compressed Frame Player Animation Without Frames"
            (animation_id: u8, fps: u8, fade: bool, data: Bytes) -> ();
        0x42 set_compressed_frame_player_single_character "Set Compressed Frame Player Single Character" (red: u8, green: u8, blue: u8,
            character: Char) -> ();
        0x43 play_compressed_frame_player_animation_with_loop_option "Play Compressed Frame Player Animation With Loop Option"
            (animation_id: u8, repeat: bool = "true") -> ();
        0x44 get_active_color_palette "Get Active Color Palette" () -> (data: Bytes);
        0x45 set_active_color_palette "Set Active Color Palette" (data: Bytes) -> ();
        0x46 get_color_identification_report "Get Color Identification Report" (red: u8, green: u8, blue: u8,
            confidence_threshold: u8) -> (data: Bytes);
        0x47 load_color_palette "Load Color Palette" (palette_index: u8) -> ();
        0x48 save_color_palette "Save Color Palette" (palette_index: u8) -> ();
        0x4C get_compressed_frame_player_frame_info_type "Get Compressed Frame Player Frame Info Type" () -> (info_type: FrameInfoType);
        0x4D save_compressed_frame_player_16_bit_frame "Save Compressed Frame Player 16 Bit Frame" (words: U16List) -> (data: Bytes);
        0x4E release_led_requests "Release LED Requests" () -> ();
    }
}
