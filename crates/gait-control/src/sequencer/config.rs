//! The sequencer's thresholds and timings.

/// Thresholds and timings of gait execution.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct SequencerConfig {
    /// Each crutch must carry at least this before a swing starts, N.
    pub crutch_ready_n: f32,
    /// The feet together must carry at least this before a swing starts,
    /// N: the device stands on the ground. How the weight is split between
    /// them is the table's plan (a step may start with the weight on the
    /// trailing foot and shift it in double support before the lift-off).
    pub feet_ready_n: f32,
    /// Swing-foot force that counts as ground contact, N.
    pub landing_contact_n: f32,
    /// A landing is the contact held this long, s: a force sensor's spike
    /// of a few milliseconds late in a swing (a connector's glitch, a
    /// brush against the riser) is not the ground. Taken for a landing,
    /// it swapped the legs with the foot still in the air, and on stairs
    /// the torso tipped over the stance leg it had just left.
    pub landing_confirm_s: f32,
    /// Landing is accepted from this fraction of the table's duration on
    /// (earlier contact is a scuff, not a landing).
    pub landing_window_fraction: f32,
    /// After the table ends, how long to wait for contact before giving up
    /// and holding the posture, s.
    pub landing_timeout_s: f32,
    /// A swing foot whose force sensor is lost (or the whole ADC) cannot
    /// report its contact: the step counts as landed this long after the
    /// table's end, s. The foot reaches the tread behind its reference (on
    /// the shipped tables, healthy landings are sensed 0.08–0.24 s after
    /// the table's end): counted at the end itself, the weight transfer
    /// started with the foot still above a stair's tread and moved the body
    /// onto a leg that was not yet on the ground. At most
    /// `landing_timeout_s` (a larger or NaN value is taken as it).
    pub blind_landing_settle_s: f32,
    /// After the table ends without a landing, the swing foot is left this
    /// long to settle onto the ground by itself (a foot that ends a
    /// millimetre above the tread, still moving, drifts back onto its
    /// planned point as the stance leg rolls on; set down at once, it
    /// landed 9 mm long on every stair-descent step and crept towards the
    /// nosing), s …
    pub ground_search_after_s: f32,
    /// … then goes on down looking for the ground by up to this (less
    /// where the knee would straighten), m …
    pub ground_search_depth_m: f32,
    /// … over this time (eased in and out), s; then it waits there for the
    /// rest of the landing timeout.
    pub ground_search_s: f32,
    /// Largest joint-angle difference from a table's start posture that
    /// still counts as "in the start posture", rad.
    pub start_tolerance_rad: f32,
    /// Duration of the weight transfer between steps, s.
    pub transfer_s: f32,
    /// The stance ankle must be within this of the table's stance-shank
    /// angle at the start (φ1(0)) before a swing starts, rad: the body is
    /// over the stance foot where the step was planned from. A swing that
    /// starts with the shank elsewhere pitches the torso by the difference
    /// (the joints follow the table, the pilot sets φ1).
    pub start_ankle_tolerance_rad: f32,
    /// Duration of the ramp into a safe hold, s.
    pub hold_ramp_s: f32,
    /// A safe hold that strikes in a swing sets the swing foot down
    /// straight below where it is, by up to this (less where the knee
    /// would straighten), until its sensor feels the ground, m …
    pub set_down_depth_m: f32,
    /// … over this time (eased in and out), s: held in the air, a foot
    /// leaves the whole body on the stance leg, whose hip alone then
    /// carries the torso (docs/safety.md).
    pub set_down_s: f32,
    /// … its swing hip and knee references moving no faster than this,
    /// rad/s: where the leg nears its reach, the knee's angle changes ever
    /// faster for the same fall of the ankle, past what its drive can
    /// follow (docs/safety.md, "Swing").
    pub set_down_joint_speed_rad_s: f32,
    /// From this fraction of a swing on (walk, stair ascent, stair
    /// descent), a safe hold plays the step on to its landing first,
    /// whatever the fault, while the stance knee has its drive and encoder
    /// (1 or more: never; `Sequencer::in_swing_now`).
    pub lands_after: [f32; 3],
    /// In a safe hold, a stance shank measured further forward than the
    /// hold's plan by more than this turns the torso back by the excess
    /// ([`Sequencer::level_torso`](super::Sequencer)), rad: a pilot who leans
    /// takes the shank forward, and with hips and knees held the torso
    /// pitches with it until the stance hip cannot carry it (194 N·m ×
    /// sin(pitch) against a 150 N·m drive) …
    pub level_deadband_rad: f32,
    /// … by at most this, rad …
    pub level_max_rad: f32,
    /// … at most this fast, rad/s: a faster turn of the torso asks the hip
    /// for the torque that tips it (of the campaigns' leaning runs, more
    /// fell at 3 rad/s than at 0.7, and at 0.35 too, the torso left
    /// pitched longer).
    pub level_rate_rad_s: f32,
}

impl SequencerConfig {
    /// Defaults for a 93 kg system: 60 N per crutch and 300 N on the stance
    /// foot to be "ready", 80 N of swing-foot force for contact, held 8 ms
    /// (a landing's force, once there, stays; the campaign's spikes last
    /// 3 ms) for a landing,
    /// accepted after 60 % of the step (a blind one 0.3 s after the
    /// table's end), 1.5 s timeout, a ground search from
    /// 0.5 s after the table's end of up to 5 cm over 0.8 s (at most 9.4
    /// cm/s, slower the nearer the ground is), 0.15 rad start
    /// tolerance, 0.4 s transfer, stance ankle within 0.05 rad (2.9°) of
    /// the table's start, 0.3 s hold ramp, a set-down of up to 20 cm over
    /// 0.8 s (at most 0.375 m/s), its joints at most 2 rad/s; a hold in the
    /// last 35 % of a stair descent's swing lands the step first; a hold
    /// turns the torso back by a stance shank's lean past 0.03 rad, by up
    /// to 0.35 rad, at 0.7 rad/s.
    pub const DEFAULT: Self = Self {
        crutch_ready_n: 60.0,
        feet_ready_n: 400.0,
        landing_contact_n: 80.0,
        landing_confirm_s: 0.008,
        landing_window_fraction: 0.6,
        landing_timeout_s: 1.5,
        blind_landing_settle_s: 0.3,
        ground_search_after_s: 0.5,
        ground_search_depth_m: 0.05,
        ground_search_s: 0.8,
        start_tolerance_rad: 0.15,
        transfer_s: 0.4,
        start_ankle_tolerance_rad: 0.05,
        hold_ramp_s: 0.3,
        set_down_depth_m: 0.2,
        set_down_s: 0.8,
        set_down_joint_speed_rad_s: 2.0,
        lands_after: [1.0, 1.0, 0.65],
        level_deadband_rad: 0.03,
        level_max_rad: 0.35,
        level_rate_rad_s: 0.7,
    };
}
