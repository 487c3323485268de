//! The terminal the TUI owns: raw mode, alternate screen, focus events, the kitty keyboard
//! protocol when the terminal supports it, and restoring all of it on every exit path
//! (normal exit, error, signal, panic).

use crossterm::event::{
    DisableFocusChange, DisableMouseCapture, EnableFocusChange, EnableMouseCapture,
    KeyboardEnhancementFlags, PopKeyboardEnhancementFlags, PushKeyboardEnhancementFlags,
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
            EnableMouseCapture,
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
    let _ = execute!(
        out,
        DisableMouseCapture,
        DisableFocusChange,
        LeaveAlternateScreen,
        cursor::Show
    );
    let _ = out.flush();
    let _ = disable_raw_mode();
}

/// Whether the TUI currently owns the terminal.
pub fn active() -> bool {
    ACTIVE.load(Ordering::SeqCst)
}

impl TerminalGuard {
    /// How key releases are known on this terminal: reported (kitty protocol), or inferred
    /// from the end of auto-repeat with the configured delays.
    pub fn release_mode(
        &self,
        keyboard: &crate::config::Keyboard,
    ) -> crate::teleop::held::ReleaseMode {
        use crate::teleop::held::ReleaseMode;
        use std::time::Duration;
        if self.release_events {
            ReleaseMode::Reported
        } else {
            ReleaseMode::Emulated {
                first: Duration::from_millis(keyboard.release_first_ms),
                repeat: Duration::from_millis(keyboard.release_repeat_ms),
            }
        }
    }
}

/// Terminal input as app events, read on a task of its own until the receiver goes.
pub fn spawn_reader() -> (
    tokio::sync::mpsc::Receiver<crate::app::input::TermEvent>,
    tokio::task::JoinHandle<()>,
) {
    use futures_util::StreamExt;
    let (tx, rx) = tokio::sync::mpsc::channel(256);
    let reader = tokio::spawn(async move {
        let mut events = crossterm::event::EventStream::new();
        while let Some(Ok(e)) = events.next().await {
            if let Some(e) = crate::app::input::from_crossterm(&e)
                && tx.send(e).await.is_err()
            {
                break;
            }
        }
    });
    (rx, reader)
}
