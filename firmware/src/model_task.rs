//! The model task on the board (`gait_control::feedforward`): the
//! supervisor's windowed checks of the tick's facts and the model's
//! feed-forward for the next tick, worked out in PendSV, which the tick's
//! interrupt pends as it ends and preempts whenever it comes. PendSV is put
//! below every interrupt, so it runs after the tick returns and before
//! thread mode (the re-planner) goes on; the two share only the
//! [`ModelSlot`] (atomics, and the check slot's critical sections).

use cortex_m::peripheral::SCB;
use gait_control::feedforward::{ModelSlot, ModelTask};

use crate::tick_state::TickState;

/// The slot the tick and the model task share.
pub static SLOT: ModelSlot = ModelSlot::new();

/// The task, until PendSV first runs and takes it.
static PLACED: TickState<ModelTask<'static>> = TickState::new();

/// PendSV's priority: the lowest (the tick's interrupt keeps the reset
/// value, the highest). Each board sets it (`SCB::set_priority`) before it
/// unmasks the tick.
pub const PRIORITY: u8 = 0xF0;

/// Hands `task` to PendSV. Call before the tick's interrupt is unmasked;
/// `false` if a task is already placed.
pub fn install(task: ModelTask<'static>) -> bool {
    PLACED.place(task)
}

/// The tick's last step: asks for the model's answer before the next tick.
pub fn pend() {
    SCB::set_pendsv();
}

/// PendSV's body, on the task the handler keeps (`task`, `None` until its
/// first run takes the placed one, in a critical section of a few
/// instructions, once).
pub fn serve(task: &mut Option<ModelTask<'static>>) {
    if task.is_none() {
        *task = PLACED.take();
    }
    if let Some(t) = task {
        t.serve();
    }
}
