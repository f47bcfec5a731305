//! Generates the DBC description of the pose layout (`config/can/eventtrack6d.dbc` is this text for the default
//! base identifier; a test keeps the two identical).

use super::layout::{
    CLASSIC_LEN, ClassicKind, DEFAULT_BASE_ID, FD_LEN, MAX_OBJECTS, classic_id, fd_id,
};
use std::fmt::Write as _;

struct Sig {
    name: &'static str,
    start: u32,
    size: u32,
    signed: bool,
    factor: &'static str,
    min: &'static str,
    max: &'static str,
    unit: &'static str,
    comment: &'static str,
}

#[allow(clippy::too_many_arguments)] // a table row: one argument per DBC column
const fn sig(
    name: &'static str,
    start: u32,
    size: u32,
    signed: bool,
    factor: &'static str,
    range: (&'static str, &'static str),
    unit: &'static str,
    comment: &'static str,
) -> Sig {
    Sig {
        name,
        start,
        size,
        signed,
        factor,
        min: range.0,
        max: range.1,
        unit,
        comment,
    }
}

const CRC: Sig = sig(
    "CRC",
    0,
    8,
    false,
    "1",
    ("0", "255"),
    "",
    "CRC-8/AUTOSAR (poly 0x2F, init 0xFF, xorout 0xFF, not reflected) over the CAN id as 2 bytes (low byte first) \
     then bytes 1 to end of this frame.",
);
const COUNTER: Sig = sig(
    "Counter",
    8,
    8,
    false,
    "1",
    ("0", "255"),
    "",
    "Rolling counter: tick index mod 256. Identical in all frames of one pose; assemble only frames with equal \
     counters.",
);
const C_POS: [Sig; 3] = [
    sig(
        "PosX",
        16,
        24,
        true,
        "0.00001",
        ("-83.88608", "83.88607"),
        "m",
        "Position x of T_cam_obj (camera frame, x right), 0.01 mm.",
    ),
    sig(
        "PosY",
        40,
        24,
        true,
        "0.00001",
        ("-83.88608", "83.88607"),
        "m",
        "Position y of T_cam_obj (camera frame, y down), 0.01 mm.",
    ),
    sig(
        "PosZ",
        16,
        24,
        true,
        "0.00001",
        ("-83.88608", "83.88607"),
        "m",
        "Position z of T_cam_obj (camera frame, z forward), 0.01 mm.",
    ),
];
const C_QUALITY: Sig = sig(
    "Quality",
    40,
    8,
    false,
    "0.004",
    ("0", "1"),
    "",
    "Tracking quality in [0, 1] (raw 0..250).",
);
const C_STATE: Sig = sig(
    "State",
    48,
    8,
    false,
    "1",
    ("0", "2"),
    "",
    "Tracking state: 0 tracking, 1 degraded, 2 lost (do not use for control).",
);
const C_OBJECT: Sig = sig(
    "Object",
    56,
    8,
    false,
    "1",
    ("0", "15"),
    "",
    "Object index (repeats the index encoded in the CAN id).",
);
const Q_COMMENT: &str =
    "Unit quaternion component of the rotation of T_cam_obj, w >= 0; renormalise after decoding.";
const C_QUAT: [Sig; 4] = [
    sig(
        "QuatX",
        16,
        16,
        true,
        "0.000030517578125",
        ("-1", "1"),
        "",
        Q_COMMENT,
    ),
    sig(
        "QuatY",
        32,
        16,
        true,
        "0.000030517578125",
        ("-1", "1"),
        "",
        Q_COMMENT,
    ),
    sig(
        "QuatZ",
        48,
        16,
        true,
        "0.000030517578125",
        ("-1", "1"),
        "",
        Q_COMMENT,
    ),
    sig(
        "QuatW",
        16,
        16,
        true,
        "0.000030517578125",
        ("-1", "1"),
        "",
        Q_COMMENT,
    ),
];
const C_TIME: Sig = sig(
    "TimeUs",
    32,
    32,
    false,
    "1",
    ("0", "4294967295"),
    "us",
    "Low 32 bits of the pose time on the event camera clock (wraps every 4294.967296 s).",
);

const F_QF: &str = "0.000000000931322574615478515625";
const F_Q_COMMENT: &str =
    "Unit quaternion component (2^-30 per bit) of the rotation of T_cam_obj, w >= 0.";
const FD_SIGNALS: [Sig; 14] = [
    CRC,
    COUNTER,
    sig(
        "State",
        16,
        8,
        false,
        "1",
        ("0", "2"),
        "",
        "Tracking state: 0 tracking, 1 degraded, 2 lost (do not use for control).",
    ),
    sig(
        "Object",
        24,
        8,
        false,
        "1",
        ("0", "15"),
        "",
        "Object index (repeats the index encoded in the CAN id).",
    ),
    sig(
        "Quality",
        32,
        16,
        false,
        "0.0001",
        ("0", "1"),
        "",
        "Tracking quality in [0, 1] (raw 0..10000).",
    ),
    sig(
        "TimeUs",
        64,
        64,
        true,
        "1",
        ("-9223372036854775808", "9223372036854775807"),
        "us",
        "Pose time on the event camera clock, microseconds.",
    ),
    sig(
        "TickIndex",
        128,
        32,
        false,
        "1",
        ("0", "4294967295"),
        "",
        "Low 32 bits of the 120 Hz tick index.",
    ),
    sig(
        "PosX",
        160,
        32,
        true,
        "0.000001",
        ("-2147.483648", "2147.483647"),
        "m",
        "Position x of T_cam_obj (camera frame, x right), 1 um.",
    ),
    sig(
        "PosY",
        192,
        32,
        true,
        "0.000001",
        ("-2147.483648", "2147.483647"),
        "m",
        "Position y of T_cam_obj (camera frame, y down), 1 um.",
    ),
    sig(
        "PosZ",
        224,
        32,
        true,
        "0.000001",
        ("-2147.483648", "2147.483647"),
        "m",
        "Position z of T_cam_obj (camera frame, z forward), 1 um.",
    ),
    sig("QuatX", 256, 32, true, F_QF, ("-2", "2"), "", F_Q_COMMENT),
    sig("QuatY", 288, 32, true, F_QF, ("-2", "2"), "", F_Q_COMMENT),
    sig("QuatZ", 320, 32, true, F_QF, ("-2", "2"), "", F_Q_COMMENT),
    sig("QuatW", 352, 32, true, F_QF, ("-2", "2"), "", F_Q_COMMENT),
];

const TX: &str = "EventTrack6D";

fn classic_signals(kind: ClassicKind) -> Vec<&'static Sig> {
    let mut v = vec![&CRC, &COUNTER];
    match kind {
        ClassicKind::PosXy => v.extend([&C_POS[0], &C_POS[1]]),
        ClassicKind::PosZStatus => v.extend([&C_POS[2], &C_QUALITY, &C_STATE, &C_OBJECT]),
        ClassicKind::QuatXyz => v.extend([&C_QUAT[0], &C_QUAT[1], &C_QUAT[2]]),
        ClassicKind::QuatWTime => v.extend([&C_QUAT[3], &C_TIME]),
    }
    v
}

fn kind_name(kind: ClassicKind) -> (&'static str, &'static str) {
    match kind {
        ClassicKind::PosXy => ("PosXY", "position x, y"),
        ClassicKind::PosZStatus => ("PosZStatus", "position z, quality, state, object index"),
        ClassicKind::QuatXyz => ("QuatXYZ", "quaternion x, y, z"),
        ClassicKind::QuatWTime => ("QuatWTime", "quaternion w, pose time low 32 bits"),
    }
}

/// The DBC text for the layout at `base_id` with `objects` objects (at most [`MAX_OBJECTS`]).
pub fn dbc_text(base_id: u16, objects: usize) -> String {
    let objects = objects.min(MAX_OBJECTS);
    let mut messages = Vec::new(); // (id, name, len, fd, comment, signals)
    for n in 0..objects {
        for kind in ClassicKind::ALL {
            let (suffix, what) = kind_name(kind);
            messages.push((
                classic_id(base_id, n, kind),
                format!("ET6D_O{n}_{suffix}"),
                CLASSIC_LEN,
                false,
                format!(
                    "Object {n} pose, classic CAN frame {} of 4: {what}. 120 Hz.",
                    kind as u8 + 1
                ),
                classic_signals(kind),
            ));
        }
    }
    for n in 0..objects {
        messages.push((
            fd_id(base_id, n),
            format!("ET6D_O{n}_PoseFD"),
            FD_LEN,
            true,
            format!("Object {n} pose in one CAN FD frame (48 bytes, BRS). 120 Hz."),
            FD_SIGNALS.iter().collect(),
        ));
    }

    let mut s = String::new();
    s.push_str("VERSION \"EventTrack6D pose layout 1\"\n\n\nNS_ :\n");
    for ns in [
        "NS_DESC_",
        "CM_",
        "BA_DEF_",
        "BA_",
        "VAL_",
        "CAT_DEF_",
        "CAT_",
        "FILTER",
        "BA_DEF_DEF_",
        "EV_DATA_",
        "ENVVAR_DATA_",
        "SGTYPE_",
        "SGTYPE_VAL_",
        "BA_DEF_SGTYPE_",
        "BA_SGTYPE_",
        "SIG_TYPE_REF_",
        "VAL_TABLE_",
        "SIG_GROUP_",
        "SIG_VALTYPE_",
        "SIGTYPE_VALTYPE_",
        "BO_TX_BU_",
        "BA_DEF_REL_",
        "BA_REL_",
        "BA_DEF_DEF_REL_",
        "BU_SG_REL_",
        "BU_EV_REL_",
        "BU_BO_REL_",
        "SG_MUL_VAL_",
    ] {
        let _ = writeln!(s, "\t{ns}");
    }
    let _ = writeln!(s, "\nBS_:\n\nBU_: {TX}\n");
    for (id, name, len, _, _, sigs) in &messages {
        let _ = writeln!(s, "BO_ {id} {name}: {len} {TX}");
        for g in sigs {
            let sign = if g.signed { '-' } else { '+' };
            let _ = writeln!(
                s,
                " SG_ {} : {}|{}@1{} ({},0) [{}|{}] \"{}\" Vector__XXX",
                g.name, g.start, g.size, sign, g.factor, g.min, g.max, g.unit
            );
        }
        s.push('\n');
    }
    let _ = writeln!(
        s,
        "\nCM_ \"EventTrack6D object poses T_cam_obj (OpenCV camera frame, metres) at 120 Hz. Classic CAN: 4 frames per \
         object at base+4n+k; CAN FD: one frame per object at base+64+n. Base id {base_id:#X}. All signals little \
         endian. See docs/can.md.\";"
    );
    let _ = writeln!(s, "CM_ BU_ {TX} \"The EventTrack6D tracker process.\";");
    for (id, _, _, _, comment, sigs) in &messages {
        let _ = writeln!(s, "CM_ BO_ {id} \"{comment}\";");
        for g in sigs {
            let _ = writeln!(s, "CM_ SG_ {id} {} \"{}\";", g.name, g.comment);
        }
    }
    s.push_str(
        "BA_DEF_ BO_ \"VFrameFormat\" ENUM \"StandardCAN\",\"ExtendedCAN\",\"reserved\",\"reserved\",\"reserved\",\
         \"reserved\",\"reserved\",\"reserved\",\"reserved\",\"reserved\",\"reserved\",\"reserved\",\"reserved\",\
         \"reserved\",\"StandardCAN_FD\",\"ExtendedCAN_FD\";\n",
    );
    s.push_str("BA_DEF_ BO_ \"GenMsgCycleTime\" INT 0 65535;\n");
    s.push_str("BA_DEF_ \"BusType\" STRING ;\n");
    s.push_str("BA_DEF_ \"DBName\" STRING ;\n");
    s.push_str("BA_DEF_DEF_ \"VFrameFormat\" \"StandardCAN\";\n");
    s.push_str("BA_DEF_DEF_ \"GenMsgCycleTime\" 0;\n");
    s.push_str("BA_DEF_DEF_ \"BusType\" \"CAN\";\n");
    s.push_str("BA_DEF_DEF_ \"DBName\" \"\";\n");
    s.push_str("BA_ \"BusType\" \"CAN FD\";\n");
    s.push_str("BA_ \"DBName\" \"EventTrack6D\";\n");
    for (id, _, _, fd, _, _) in &messages {
        let _ = writeln!(s, "BA_ \"GenMsgCycleTime\" BO_ {id} 8;");
        if *fd {
            let _ = writeln!(s, "BA_ \"VFrameFormat\" BO_ {id} 14;");
        }
    }
    for (id, _, _, _, _, sigs) in &messages {
        if sigs.iter().any(|g| g.name == "State") {
            let _ = writeln!(
                s,
                "VAL_ {id} State 0 \"tracking\" 1 \"degraded\" 2 \"lost\" ;"
            );
        }
    }
    s
}

/// The DBC text shipped as `config/can/eventtrack6d.dbc` (base 0x300, all objects).
pub fn default_dbc_text() -> String {
    dbc_text(DEFAULT_BASE_ID, MAX_OBJECTS)
}
