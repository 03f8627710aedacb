//! The fault table in `docs/safety.md` and the one in `faults.rs` agree,
//! row for row: the same codes (each once), and for each code the same
//! name, reaction, detection bound and reset rule.

use gait_control::faults::{FaultCode, Reaction};

const SAFETY_MD: &str = include_str!("../../../../docs/safety.md");

const HEADER: &str =
    "| code | name | condition | detection bound | reaction | reset allowed when |";

/// One row of the doc's table, its cells with `\|` unescaped.
#[derive(Debug)]
struct DocRow {
    line: usize,
    code: u16,
    name: String,
    detection_bound: String,
    reaction: String,
    reset_allowed_when: String,
}

/// Splits a Markdown table row on the pipes that are not escaped.
fn cells(line: &str) -> Vec<String> {
    let inner = line
        .trim()
        .strip_prefix('|')
        .and_then(|l| l.strip_suffix('|'))
        .unwrap_or_else(|| panic!("not a table row: {line}"));
    let mut out = vec![String::new()];
    let mut chars = inner.chars().peekable();
    while let Some(c) = chars.next() {
        match c {
            '\\' if chars.peek() == Some(&'|') => {
                out.last_mut().unwrap().push('|');
                chars.next();
            }
            '|' => out.push(String::new()),
            c => out.last_mut().unwrap().push(c),
        }
    }
    out.iter().map(|c| c.trim().to_owned()).collect()
}

/// The rows of the table under `## Fault table`.
fn doc_rows() -> Vec<DocRow> {
    let mut lines = SAFETY_MD
        .lines()
        .enumerate()
        .skip_while(|(_, l)| l.trim() != "## Fault table")
        .skip_while(|(_, l)| !l.starts_with('|'));
    let (_, header) = lines.next().expect("no table under `## Fault table`");
    assert_eq!(header.trim(), HEADER, "the fault table's columns changed");
    let (_, rule) = lines.next().expect("no header rule");
    assert!(rule.starts_with("|---"), "{rule}");
    lines
        .take_while(|(_, l)| l.starts_with('|'))
        .map(|(i, l)| {
            let c = cells(l);
            assert_eq!(c.len(), 6, "line {}: {} cells, want 6: {l}", i + 1, c.len());
            let hex = c[0]
                .strip_prefix("0x")
                .unwrap_or_else(|| panic!("line {}: code {:?} is not 0x…", i + 1, c[0]));
            DocRow {
                line: i + 1,
                code: u16::from_str_radix(hex, 16)
                    .unwrap_or_else(|e| panic!("line {}: code {:?}: {e}", i + 1, c[0])),
                name: c[1].clone(),
                detection_bound: c[3].clone(),
                reaction: c[4].clone(),
                reset_allowed_when: c[5].clone(),
            }
        })
        .collect()
}

/// How the doc writes a fault's reaction.
fn doc_label(r: Reaction) -> &'static str {
    match r {
        Reaction::None => "NONE",
        Reaction::PlayTable => "PLAY THE TABLE",
        Reaction::FinishStepThenHold => "FINISH STEP, THEN HOLD",
        Reaction::SafeHold => "SAFE HOLD",
        Reaction::DisableMotors => "MOTORS DISABLED",
    }
}

#[test]
fn the_doc_lists_every_code_once_in_code_order() {
    let rows = doc_rows();
    for w in rows.windows(2) {
        assert!(
            w[0].code < w[1].code,
            "line {}: 0x{:04x} after 0x{:04x} (the doc's table is in code order, each code once)",
            w[1].line,
            w[1].code,
            w[0].code
        );
    }
    let hex = |codes: &mut dyn Iterator<Item = u16>| {
        let mut v: Vec<u16> = codes.collect();
        v.sort_unstable();
        v.iter().map(|c| format!("0x{c:04x}")).collect::<Vec<_>>()
    };
    let doc = hex(&mut rows.iter().map(|r| r.code));
    let code = hex(&mut FaultCode::ALL.iter().map(|c| c.code()));
    assert_eq!(doc, code, "docs/safety.md's codes vs FaultCode::ALL");
    assert_eq!(rows.len(), FaultCode::COUNT);
}

#[test]
fn each_doc_row_matches_its_code_row() {
    let rows = doc_rows();
    assert!(!rows.is_empty());
    for row in &rows {
        let at = format!("docs/safety.md line {} (0x{:04x})", row.line, row.code);
        let c = FaultCode::from_code(row.code).unwrap_or_else(|| panic!("{at}: no such FaultCode"));
        assert_eq!(row.name, c.name(), "{at}: name");
        let mut label = match c.in_swing() {
            gait_control::faults::InSwing::LandFirst => {
                format!("{} (IN A SWING: LAND FIRST)", doc_label(c.reaction()))
            }
            gait_control::faults::InSwing::HoldNow => doc_label(c.reaction()).to_owned(),
        };
        if c.brakes_joint() {
            label.push_str(", THAT JOINT BRAKED");
        }
        if c.held_in_place_first() {
            label.push_str(" (ANOTHER ALREADY BRAKED: HELD IN PLACE FIRST)");
        }
        assert_eq!(row.reaction, label, "{at}: reaction");
        assert_eq!(
            row.detection_bound,
            c.detection_bound(),
            "{at}: detection bound"
        );
        assert_eq!(
            row.reset_allowed_when,
            c.reset_rule(),
            "{at}: reset allowed when"
        );
    }
}

#[test]
fn no_fault_reacts_with_none() {
    // `Reaction::None` means "nothing latched"; a fault must do something.
    for c in FaultCode::ALL {
        assert_ne!(c.reaction(), Reaction::None, "{c:?}");
    }
}

#[test]
fn the_cell_splitter_keeps_escaped_pipes() {
    assert_eq!(
        cells(r"| a | \|x\| > 1 | b |"),
        vec!["a".to_owned(), "|x| > 1".to_owned(), "b".to_owned()]
    );
}

#[test]
fn only_safe_holds_land_first_and_only_for_missed_deadlines_late_checks_jumps_and_balance() {
    use gait_control::faults::InSwing;
    let landing: Vec<FaultCode> = FaultCode::ALL
        .into_iter()
        .filter(|c| c.in_swing() == InSwing::LandFirst)
        .collect();
    assert!(landing.iter().all(|c| c.reaction() == Reaction::SafeHold));
    assert_eq!(
        landing.iter().map(|c| c.code()).collect::<Vec<_>>(),
        [0x0205, 0x0601, 0x0608, 0x0701]
    );
    // A set lands first only if every safe-hold fault in it does.
    let mut set: gait_control::faults::FaultSet = [FaultCode::DeadlineMissed, FaultCode::ForceOpen]
        .into_iter()
        .collect();
    assert_eq!(set.in_swing(), InSwing::LandFirst);
    // A saturated drive sets the foot down (a weak stance hip needs the
    // second foot), and so does the set with it.
    set.insert(FaultCode::MotorSaturated);
    assert_eq!(set.in_swing(), InSwing::HoldNow);
}

#[test]
fn a_sets_reaction_is_its_most_severe_codes() {
    use gait_control::faults::FaultSet;
    // The set's reaction (masks made when compiling) against the plain
    // maximum over its codes: the empty set, every code alone, every pair,
    // and pseudo-random sets.
    let plain = |set: FaultSet| {
        set.iter()
            .map(FaultCode::reaction)
            .max()
            .unwrap_or(Reaction::None)
    };
    assert_eq!(FaultSet::EMPTY.reaction(), Reaction::None);
    for &a in FaultCode::ALL.iter() {
        for &b in FaultCode::ALL.iter() {
            let set: FaultSet = [a, b].into_iter().collect();
            assert_eq!(set.reaction(), plain(set), "{a:?} {b:?}");
        }
    }
    let mut x = 0x9e37_79b9_7f4a_7c15_u64;
    for _ in 0..2000 {
        x ^= x << 13;
        x ^= x >> 7;
        x ^= x << 17;
        let set: FaultSet = FaultCode::ALL
            .iter()
            .enumerate()
            .filter(|(i, _)| x >> i & 1 == 1)
            .map(|(_, &c)| c)
            .collect();
        assert_eq!(set.reaction(), plain(set), "{set:?}");
    }
}

#[test]
fn codes_are_stable_unique_and_grouped() {
    // Codes unique, grouped, round-trip; ALL agrees with index().
    for (i, c) in FaultCode::ALL.iter().enumerate() {
        assert_eq!(usize::from(c.index()), i);
        assert_eq!(FaultCode::from_code(c.code()), Some(*c));
        assert!(matches!(c.code() >> 8, 0x01..=0x07), "{c:?}");
        assert!(!c.name().is_empty());
    }
    assert_eq!(FaultCode::EStopPressed.code(), 0x0501);
    assert_eq!(FaultCode::JointPositionLimit.code(), 0x0101);
    assert_eq!(FaultCode::from_code(0x0000), None);
}
