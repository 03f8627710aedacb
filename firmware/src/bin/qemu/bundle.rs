//! The QEMU image's check of the patient's bundle in its sector.

use core::hint::black_box;

use exogait_device::boot::{self, Gaits};
use firmware::{board_config, flash_sectors, qemu_bundle};
use gait_control::faults::Reaction;

use crate::{InstrCounter, Out, line, phase_name};

/// The patient's bundle in its sector (`exogait_device::boot`): none (the
/// built-in tables), refused (the board must hold, GO ignored) or verified
/// (its gaits listed, its first gait's step replayed against the host's).
/// Returns the number of failures.
pub(crate) fn check(out: &mut Out, ctr: &mut InstrCounter) -> usize {
    let Ok(device) = board_config::device() else {
        out.put(&mut line("FAIL bundle: device configuration refused"));
        return 1;
    };
    let gaits = boot::gaits_in(&device, flash_sectors::bundle());
    match &gaits {
        Gaits::BuiltIn => {
            out.put(&mut line("bundle: none (the device's built-in tables)"));
            0
        }
        Gaits::Refused(e) => {
            out.put(line("bundle: refused reason=").str(e.reason()));
            match qemu_bundle::refused_board(&device, &gaits) {
                Ok(h) if !h.stepped && h.refusal_latched && h.reaction == Reaction::SafeHold => {
                    out.put(
                        line("bundle: board holds, GO ignored (")
                            .u32(h.ticks)
                            .str(" ticks, phase ")
                            .str(phase_name(&h.phase))
                            .str(", 0x0604 latched, motors enabled ")
                            .str(if h.motors_enabled { "true" } else { "false" })
                            .str(")"),
                    );
                    0
                }
                _ => {
                    out.put(&mut line(
                        "FAIL bundle: a refused bundle did not leave the board holding",
                    ));
                    1
                }
            }
        }
        Gaits::Patient(b) => {
            out.put(
                line("bundle: ok gaits=")
                    .usize(b.len())
                    .str(" crc=")
                    .hex(b.crc(), 8),
            );
            for (i, g) in (0..b.len()).filter_map(|i| b.gait(i)).enumerate() {
                out.put(
                    line("bundle: gait ")
                        .usize(i + 1)
                        .str(" name=")
                        .str(g.info.name.as_str())
                        .str(" flashes=")
                        .usize(i + 1),
                );
            }
            let base = ctr.once(|| black_box(0u32)).0;
            let played = qemu_bundle::play_step(&device, &gaits, |tick| {
                let (instr, report) = ctr.once(tick);
                (instr.saturating_sub(base), report)
            });
            match played {
                Ok(None) => {
                    out.put(&mut line("bundle: no step recording loaded"));
                    0
                }
                Ok(Some(r)) => {
                    let swing = r.phases.get(2).map_or(0, |p| p.ticks);
                    let first = b.gait(0).map(|g| g.info.name);
                    let worst = r.phases.iter().map(|p| p.worst).max().unwrap_or(0);
                    out.put(
                        line("bundle: played gait=")
                            .str(first.as_ref().map_or("?", |n| n.as_str()))
                            .str(" ticks=")
                            .u32(r.ticks)
                            .str(" swing_ticks=")
                            .u32(swing)
                            .str(" worst_tick_instr=")
                            .u32(worst)
                            .str(" differing_ticks=")
                            .u32(r.differing_ticks)
                            .str(" max_command_diff_nm=")
                            .exp(r.max_command_diff_nm),
                    );
                    usize::from(swing == 0 || r.differing_ticks > 0)
                }
                Err(_) => {
                    out.put(&mut line(
                        "FAIL bundle: the step recording could not be replayed",
                    ));
                    1
                }
            }
        }
    }
}
