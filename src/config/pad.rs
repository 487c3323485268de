//! Gamepad buttons and what the configuration binds to them, parsed and checked when the
//! configuration loads (a mistyped button name is an error with its line, never ignored).
//! [`crate::teleop::gamepad`] maps gilrs's buttons onto these.

use std::fmt;

/// The buttons droidctl maps, named as in the configuration.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum Button {
    South,
    East,
    North,
    West,
    Start,
    Select,
    LeftBumper,
    RightBumper,
    DPadUp,
    DPadDown,
    DPadLeft,
    DPadRight,
}

impl Button {
    /// The buttons an action can be bound to (the D-pad plays the configured sounds).
    pub const BINDABLE: [Button; 8] = [
        Button::South,
        Button::East,
        Button::North,
        Button::West,
        Button::Start,
        Button::Select,
        Button::LeftBumper,
        Button::RightBumper,
    ];

    /// A bindable button by its configuration name (`South`, `RightBumper`).
    pub fn parse(name: &str) -> Option<Button> {
        Button::BINDABLE
            .into_iter()
            .find(|b| b.name() == name.trim())
    }

    pub fn name(self) -> &'static str {
        match self {
            Button::South => "South",
            Button::East => "East",
            Button::North => "North",
            Button::West => "West",
            Button::Start => "Start",
            Button::Select => "Select",
            Button::LeftBumper => "LeftBumper",
            Button::RightBumper => "RightBumper",
            Button::DPadUp => "DPadUp",
            Button::DPadDown => "DPadDown",
            Button::DPadLeft => "DPadLeft",
            Button::DPadRight => "DPadRight",
        }
    }
}

impl fmt::Display for Button {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

/// What a button press asks for.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum PadAction {
    Tripod,
    Bipod,
    Aim,
    EStop,
    Animation,
    Help,
}

impl PadAction {
    pub const ALL: [PadAction; 6] = [
        PadAction::Tripod,
        PadAction::Bipod,
        PadAction::Aim,
        PadAction::EStop,
        PadAction::Animation,
        PadAction::Help,
    ];

    /// The key in the config's `[gamepad]` table.
    pub fn config_name(self) -> &'static str {
        match self {
            PadAction::Tripod => "tripod",
            PadAction::Bipod => "bipod",
            PadAction::Aim => "aim",
            PadAction::EStop => "estop",
            PadAction::Animation => "animation",
            PadAction::Help => "help",
        }
    }

    /// What must apply for the button to be listed in help.
    pub fn needs(self) -> super::keys::Needs {
        use super::keys::Needs;
        match self {
            PadAction::Tripod | PadAction::Bipod => Needs::Legs,
            PadAction::Aim => Needs::Aim,
            PadAction::Animation => Needs::Animations,
            PadAction::EStop | PadAction::Help => Needs::All,
        }
    }

    /// For the help overlay.
    pub fn description(self) -> &'static str {
        match self {
            PadAction::Tripod => "stance: tripod",
            PadAction::Bipod => "stance: bipod",
            PadAction::Aim => "aim mode on/off (rolling droids)",
            PadAction::EStop => "EMERGENCY STOP (latched while held)",
            PadAction::Animation => "play the selected animation",
            PadAction::Help => "this help",
        }
    }
}

/// The gamepad's button bindings: one button per action, no button used twice.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct PadBindings {
    buttons: [(PadAction, Button); 6],
}

impl PadBindings {
    /// Parse the configured names, in [`PadAction::ALL`]'s order. Errors name the key.
    pub fn parse(names: [&str; 6]) -> Result<PadBindings, (String, String)> {
        let mut buttons = Vec::with_capacity(6);
        for (action, name) in PadAction::ALL.into_iter().zip(names) {
            let b = Button::parse(name).ok_or_else(|| {
                let all: Vec<&str> = Button::BINDABLE.iter().map(|b| b.name()).collect();
                (
                    action.config_name().to_string(),
                    format!("unknown button {name:?} (use {})", all.join(", ")),
                )
            })?;
            if let Some((other, _)) = buttons.iter().find(|(_, o)| *o == b) {
                let other: &PadAction = other;
                return Err((
                    action.config_name().to_string(),
                    format!(
                        "button {b} is bound to both gamepad.{} and gamepad.{}",
                        other.config_name(),
                        action.config_name()
                    ),
                ));
            }
            buttons.push((action, b));
        }
        let buttons: [(PadAction, Button); 6] = buttons
            .try_into()
            .map_err(|_| (String::new(), "six gamepad actions".to_string()))?;
        Ok(PadBindings { buttons })
    }

    /// What pressing `b` asks for.
    pub fn action(&self, b: Button) -> Option<PadAction> {
        self.buttons.iter().find(|(_, x)| *x == b).map(|(a, _)| *a)
    }

    /// The button bound to `a`.
    pub fn button(&self, a: PadAction) -> Button {
        self.buttons
            .iter()
            .find(|(x, _)| *x == a)
            .map(|(_, b)| *b)
            .unwrap_or(Button::East)
    }

    /// (button, action) in [`PadAction::ALL`]'s order, for the help overlay.
    pub fn iter(&self) -> impl Iterator<Item = (Button, PadAction)> + '_ {
        self.buttons.iter().map(|(a, b)| (*b, *a))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const DEFAULTS: [&str; 6] = ["South", "North", "RightBumper", "East", "West", "Select"];

    #[test]
    fn parses_and_maps_both_ways() {
        let p = PadBindings::parse(DEFAULTS).unwrap();
        assert_eq!(p.action(Button::RightBumper), Some(PadAction::Aim));
        assert_eq!(p.action(Button::Start), None);
        assert_eq!(p.button(PadAction::EStop), Button::East);
        assert_eq!(p.iter().count(), 6);
        assert_eq!(Button::parse("DPadUp"), None, "the D-pad plays sounds");
    }

    #[test]
    fn every_action_is_checked() {
        // Each action in turn gets a mistyped name: each one is refused, `aim` included.
        for (i, action) in PadAction::ALL.into_iter().enumerate() {
            let mut names = DEFAULTS;
            names[i] = "RightBumpr";
            let (key, msg) = PadBindings::parse(names).unwrap_err();
            assert_eq!(key, action.config_name());
            assert!(msg.contains("unknown button \"RightBumpr\""), "{msg}");
        }
    }

    #[test]
    fn one_button_one_action() {
        let names = ["South", "North", "RightBumper", "South", "West", "Select"];
        let (key, msg) = PadBindings::parse(names).unwrap_err();
        assert_eq!(key, "estop");
        assert!(
            msg.contains("gamepad.tripod") && msg.contains("gamepad.estop"),
            "{msg}"
        );
    }
}
