//! Flight-test excitations in scenarios (`[[excitation]]`): the entries and
//! their sum on the servo channels live in `helicon-setup`, which the
//! on-board program flies too; re-exported here where the simulator's users
//! find them.

pub use helicon_setup::excitation::{ExcitationEntry, Excitations, SERVOS};
