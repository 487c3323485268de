//! The terminal the TUI owns: raw mode, alternate screen, focus events, the kitty keyboard
//! protocol when the terminal supports it, and restoring all of it on every exit path
//! (normal exit, error, signal, panic).

use crossterm::event::{
    DisableFocusChange, EnableFocusChange, KeyboardEnhancementFlags, PopKeyboardEnhancementFlags,
    PushKeyboardEnhancementFlags,
};
use crossterm::terminal::{
    Clear, ClearType, EnterAlternateScreen, LeaveAlternateScreen, disable_raw_mode, enable_raw_mode,
};
use crossterm::{cursor, execute};
use std::io::{self, Write};
use std::sync::atomic::{AtomicBool, Ordering};

static ACTIVE: AtomicBool = AtomicBool::new(false);
static KITTY: AtomicBool = AtomicBool::new(false);

/// Restores the terminal when dropped.
pub struct TerminalGuard {
    /// The terminal reports key releases.
    pub release_events: bool,
}

impl TerminalGuard {
    /// Take over the terminal. Probes once whether it reports key releases (kitty keyboard
    /// protocol) and, if so, pushes the enhancement flags.
    pub fn enter() -> io::Result<TerminalGuard> {
        enable_raw_mode()?;
        ACTIVE.store(true, Ordering::SeqCst);
        let kitty = matches!(
            crossterm::terminal::supports_keyboard_enhancement(),
            Ok(true)
        );
        let mut out = io::stdout();
        execute!(
            out,
            EnterAlternateScreen,
            Clear(ClearType::All),
            EnableFocusChange,
            cursor::Hide
        )?;
        if kitty {
            execute!(
                out,
                PushKeyboardEnhancementFlags(
                    KeyboardEnhancementFlags::DISAMBIGUATE_ESCAPE_CODES
                        | KeyboardEnhancementFlags::REPORT_EVENT_TYPES
                )
            )?;
            KITTY.store(true, Ordering::SeqCst);
        }
        Ok(TerminalGuard {
            release_events: kitty,
        })
    }

    pub fn restore(&mut self) {
        restore();
    }
}

impl Drop for TerminalGuard {
    fn drop(&mut self) {
        restore();
    }
}

/// Give the terminal back: keyboard flags popped, focus events off, alternate screen left,
/// cursor shown, raw mode off. Safe to call more than once, and from a panic hook.
pub fn restore() {
    if !ACTIVE.swap(false, Ordering::SeqCst) {
        return;
    }
    let mut out = io::stdout();
    if KITTY.swap(false, Ordering::SeqCst) {
        let _ = execute!(out, PopKeyboardEnhancementFlags);
    }
    let _ = execute!(out, DisableFocusChange, LeaveAlternateScreen, cursor::Show);
    let _ = out.flush();
    let _ = disable_raw_mode();
}

/// Whether the TUI currently owns the terminal.
pub fn active() -> bool {
    ACTIVE.load(Ordering::SeqCst)
}
