//! The aircraft in 3-D for Foxglove's 3D panel: a plant's position and attitude as a `foxglove.FrameTransform`
//! (parent `world`, child `body`) and a simple aircraft of primitives with its control surfaces deflected as a
//! `foxglove.SceneUpdate` in `body`, both protobuf-encoded, with the `FileDescriptorSet` Foxglove decodes them by
//! ([`descriptor_set`]). Hand-encoded: two messages and their schemas are a few hundred lines, where a protobuf
//! library (or the Foxglove SDK) would add proc-macro crates to every clean build.
//!
//! Frames: `world` is east-north-up (x east, y north, z up, m; REP 103), from the plant's north/east position and
//! altitude; `body` is forward-left-up (x out of the nose, y out of the left wing, z up), at the plant's reference
//! point. The aerospace frames of the plant (north-east-down, forward-right-down body, Euler angles phi/theta/psi in
//! z-y-x order) map to these by swapping axes: the rotation world <- body is yaw pi/2 - psi, pitch -theta, roll phi
//! in the same z-y-x order ([`enu_flu_quaternion`]).
//!
//! Which plants: those announcing a position (`north_`, `east_`, `alt_` in `ft` or `m`) and an attitude (`phi_`,
//! `theta_`, `psi_` in `rad` or `deg`) among their outputs ([`BodySignals::resolve`]); the surfaces (`aileron_`,
//! `elevator_`, `rudder_` in `deg` or `rad`, the actuators' positions) are drawn deflected when announced, neutral
//! otherwise. Sign conventions are Stevens & Lewis': positive elevator and positive aileron on the right wing are
//! trailing edge down (the left aileron moves the other way), positive rudder is trailing edge left.

use silrig_flight::signals::PlantSignals;

/// MCAP schema encoding of the 3-D channels.
pub const SCHEMA_ENCODING: &str = "protobuf";
/// MCAP message encoding of the 3-D channels.
pub const MESSAGE_ENCODING: &str = "protobuf";
/// Schema name of the transform messages.
pub const FRAME_TRANSFORM: &str = "foxglove.FrameTransform";
/// Schema name of the aircraft's scene messages.
pub const SCENE_UPDATE: &str = "foxglove.SceneUpdate";
/// The fixed frame.
pub const WORLD_FRAME: &str = "world";
/// The aircraft's frame.
pub const BODY_FRAME: &str = "body";
/// The scene entity's id: each update replaces the aircraft drawn before.
pub const ENTITY_ID: &str = "aircraft";

const M_PER_FT: f64 = 0.3048;

/// Where a plant's position, attitude and surface positions are among its outputs, with the factor to m or rad.
#[derive(Debug, Clone, PartialEq)]
pub struct BodySignals {
    /// north, east, altitude: (output index, m per unit).
    position: [(usize, f64); 3],
    /// phi, theta, psi: (output index, rad per unit).
    attitude: [(usize, f64); 3],
    /// aileron, elevator, rudder, when announced: (output index, rad per unit).
    surfaces: [Option<(usize, f64)>; 3],
}

/// The first of `stem` with one of `units` (name suffix, factor) that `plant` announces.
fn find(plant: &PlantSignals, stem: &str, units: &[(&str, f64)]) -> Option<(usize, f64)> {
    units.iter().find_map(|(unit, factor)| plant.output(&format!("{stem}_{unit}")).ok().map(|k| (k, *factor)))
}

impl BodySignals {
    /// The position, attitude and surfaces of `plant`; `None` when it announces no position or no attitude.
    pub fn resolve(plant: &PlantSignals) -> Option<Self> {
        let length = [("m", 1.0), ("ft", M_PER_FT)];
        let angle = [("rad", 1.0), ("deg", std::f64::consts::PI / 180.0)];
        let position = [find(plant, "north", &length)?, find(plant, "east", &length)?, find(plant, "alt", &length)?];
        let attitude = [find(plant, "phi", &angle)?, find(plant, "theta", &angle)?, find(plant, "psi", &angle)?];
        let surfaces = ["aileron", "elevator", "rudder"].map(|s| find(plant, s, &angle));
        Some(Self { position, attitude, surfaces })
    }

    /// The body's position in `world` (east, north, up), m, from a sample's outputs.
    pub fn translation_m(&self, outputs: &[f64]) -> [f64; 3] {
        let [n, e, h] = self.position.map(|(k, f)| outputs[k] * f);
        [e, n, h]
    }

    /// The rotation world <- body, from a sample's outputs.
    pub fn rotation(&self, outputs: &[f64]) -> [f64; 4] {
        let [phi, theta, psi] = self.attitude.map(|(k, f)| outputs[k] * f);
        enu_flu_quaternion(phi, theta, psi)
    }

    /// aileron, elevator, rudder positions, rad (0 for a surface the plant does not announce).
    pub fn surfaces_rad(&self, outputs: &[f64]) -> [f64; 3] {
        self.surfaces.map(|s| s.map_or(0.0, |(k, f)| outputs[k] * f))
    }
}

/// The quaternion (x, y, z, w) of z-y-x Euler angles: yaw about z, then pitch about the new y, then roll about x.
fn zyx_quaternion(yaw: f64, pitch: f64, roll: f64) -> [f64; 4] {
    let (sy, cy) = (yaw / 2.0).sin_cos();
    let (sp, cp) = (pitch / 2.0).sin_cos();
    let (sr, cr) = (roll / 2.0).sin_cos();
    [sr * cp * cy - cr * sp * sy, cr * sp * cy + sr * cp * sy, cr * cp * sy - sr * sp * cy, cr * cp * cy + sr * sp * sy]
}

/// The rotation east-north-up <- forward-left-up of a body at Euler angles phi, theta, psi (rad) of the aerospace
/// convention (north-east-down <- forward-right-down, z-y-x).
pub fn enu_flu_quaternion(phi_rad: f64, theta_rad: f64, psi_rad: f64) -> [f64; 4] {
    zyx_quaternion(std::f64::consts::FRAC_PI_2 - psi_rad, -theta_rad, phi_rad)
}

/// A protobuf message being built; reused from message to message, so encoding one allocates nothing once the
/// buffers have grown.
#[derive(Debug, Default)]
pub struct ProtoBuffer {
    bytes: Vec<u8>,
    /// Where each open nested message's body starts.
    open: Vec<usize>,
}

const VARINT: u8 = 0;
const FIXED64: u8 = 1;
const LEN: u8 = 2;

impl ProtoBuffer {
    /// Start a new message.
    pub fn start(&mut self) {
        self.bytes.clear();
        self.open.clear();
    }

    /// The message so far.
    pub fn bytes(&self) -> &[u8] {
        &self.bytes
    }

    fn varint(&mut self, mut v: u64) {
        while v >= 0x80 {
            self.bytes.push(v as u8 | 0x80);
            v >>= 7;
        }
        self.bytes.push(v as u8);
    }

    fn key(&mut self, field: u32, wire_type: u8) {
        self.varint(u64::from(field) << 3 | u64::from(wire_type));
    }

    fn double(&mut self, field: u32, v: f64) {
        self.key(field, FIXED64);
        self.bytes.extend_from_slice(&v.to_le_bytes());
    }

    fn int(&mut self, field: u32, v: i64) {
        self.key(field, VARINT);
        self.varint(v as u64);
    }

    fn string(&mut self, field: u32, s: &str) {
        self.key(field, LEN);
        self.varint(s.len() as u64);
        self.bytes.extend_from_slice(s.as_bytes());
    }

    /// Open nested message `field`; [`Self::end`] closes it.
    fn begin(&mut self, field: u32) {
        self.key(field, LEN);
        self.open.push(self.bytes.len());
    }

    /// Close the innermost open message: its length goes in front of its body.
    fn end(&mut self) {
        let start = self.open.pop().expect("a nested message is open");
        let len = self.bytes.len() - start;
        let mut prefix = [0u8; 10];
        let mut n = 0;
        let mut v = len as u64;
        loop {
            prefix[n] = v as u8 | if v >= 0x80 { 0x80 } else { 0 };
            n += 1;
            v >>= 7;
            if v == 0 {
                break;
            }
        }
        self.bytes.resize(self.bytes.len() + n, 0);
        self.bytes.copy_within(start..start + len, start + n);
        self.bytes[start..start + n].copy_from_slice(&prefix[..n]);
    }

    fn timestamp(&mut self, field: u32, wall_ns: u64) {
        self.begin(field);
        self.int(1, (wall_ns / 1_000_000_000) as i64);
        self.int(2, (wall_ns % 1_000_000_000) as i64);
        self.end();
    }

    fn xyz(&mut self, field: u32, v: [f64; 3]) {
        self.begin(field);
        for (k, x) in v.into_iter().enumerate() {
            self.double(k as u32 + 1, x);
        }
        self.end();
    }

    fn xyzw(&mut self, field: u32, q: [f64; 4]) {
        self.begin(field);
        for (k, x) in q.into_iter().enumerate() {
            self.double(k as u32 + 1, x);
        }
        self.end();
    }

    /// A `foxglove.Pose` in field 1 and what follows it of a primitive.
    fn pose(&mut self, position_m: [f64; 3], orientation: [f64; 4]) {
        self.begin(1);
        self.xyz(1, position_m);
        self.xyzw(2, orientation);
        self.end();
    }
}

/// A `foxglove.FrameTransform` world -> body at `wall_ns` into `buffer`.
pub fn frame_transform(buffer: &mut ProtoBuffer, wall_ns: u64, translation_m: [f64; 3], rotation: [f64; 4]) {
    buffer.start();
    buffer.timestamp(1, wall_ns);
    buffer.string(2, WORLD_FRAME);
    buffer.string(3, BODY_FRAME);
    buffer.xyz(4, translation_m);
    buffer.xyzw(5, rotation);
}

/// Colours (r, g, b, a) of the model.
const AIRFRAME: [f64; 4] = [0.62, 0.64, 0.68, 1.0];
const SURFACE: [f64; 4] = [1.0, 0.45, 0.05, 1.0];
const CANOPY: [f64; 4] = [0.1, 0.2, 0.45, 1.0];

/// A box of the model, m in `body`.
struct Block {
    center_m: [f64; 3],
    size_m: [f64; 3],
    color: [f64; 4],
}

/// The fixed boxes: wing, fin, canopy (an F-16's size, 15 m long, 9.4 m span, reference point near the wing).
const BLOCKS: [Block; 3] = [
    Block { center_m: [-1.2, 0.0, 0.0], size_m: [3.0, 9.4, 0.15], color: AIRFRAME },
    Block { center_m: [-5.3, 0.0, 1.9], size_m: [2.4, 0.15, 2.6], color: AIRFRAME },
    Block { center_m: [3.4, 0.0, 0.75], size_m: [2.2, 0.7, 0.45], color: CANOPY },
];

/// Which way a surface turns: about the body's y axis (aileron, elevator) or its z axis (rudder).
#[derive(Clone, Copy)]
enum Hinge {
    Y,
    Z,
}

/// A moving surface: a box hinged on a line through `hinge_m` along its axis, its centre `center_aft_m` behind the
/// hinge; it turns by `sign` times a surface's position (index into aileron, elevator, rudder).
struct Surface {
    surface: usize,
    sign: f64,
    axis: Hinge,
    hinge_m: [f64; 3],
    center_aft_m: f64,
    size_m: [f64; 3],
}

/// The moving surfaces, at their trailing-edge-down (or -left) sign: a turn about +y by a positive angle lifts a
/// trailing edge, a turn about +z moves it right, so a positive deflection turns by the negative angle (the left
/// aileron, deflected opposite to the right one, by the positive one).
const SURFACES: [Surface; 5] = [
    // Ailerons, behind the wing's outer trailing edge: right (y < 0) then left.
    Surface {
        surface: 0,
        sign: -1.0,
        axis: Hinge::Y,
        hinge_m: [-2.7, -3.3, 0.0],
        center_aft_m: 0.35,
        size_m: [0.7, 2.2, 0.1],
    },
    Surface {
        surface: 0,
        sign: 1.0,
        axis: Hinge::Y,
        hinge_m: [-2.7, 3.3, 0.0],
        center_aft_m: 0.35,
        size_m: [0.7, 2.2, 0.1],
    },
    // The all-moving horizontal tail, both halves by the elevator's position.
    Surface {
        surface: 1,
        sign: -1.0,
        axis: Hinge::Y,
        hinge_m: [-5.8, -1.85, 0.0],
        center_aft_m: 0.3,
        size_m: [2.0, 2.3, 0.1],
    },
    Surface {
        surface: 1,
        sign: -1.0,
        axis: Hinge::Y,
        hinge_m: [-5.8, 1.85, 0.0],
        center_aft_m: 0.3,
        size_m: [2.0, 2.3, 0.1],
    },
    // The rudder, behind the fin.
    Surface {
        surface: 2,
        sign: -1.0,
        axis: Hinge::Z,
        hinge_m: [-6.5, 0.0, 1.7],
        center_aft_m: 0.35,
        size_m: [0.7, 0.1, 1.8],
    },
];

impl Surface {
    /// The box's centre (m) and orientation in `body` with the surfaces at `surfaces_rad`.
    fn pose(&self, surfaces_rad: [f64; 3]) -> ([f64; 3], [f64; 4]) {
        let angle = self.sign * surfaces_rad[self.surface];
        let (sin_half, cos_half) = (angle / 2.0).sin_cos();
        let (sin, cos) = angle.sin_cos();
        let aft = -self.center_aft_m;
        let [hx, hy, hz] = self.hinge_m;
        match self.axis {
            Hinge::Y => ([hx + aft * cos, hy, hz - aft * sin], [0.0, sin_half, 0.0, cos_half]),
            Hinge::Z => ([hx + aft * cos, hy + aft * sin, hz], [0.0, 0.0, sin_half, cos_half]),
        }
    }
}

/// Rotation about y by 90 degrees: a cylinder's axis (z) along the body's x.
const CYLINDER_ALONG_X: [f64; 4] = [0.0, std::f64::consts::FRAC_1_SQRT_2, 0.0, std::f64::consts::FRAC_1_SQRT_2];

/// A `foxglove.SceneUpdate` at `wall_ns` into `buffer`: the aircraft in `body` (frame-locked, so it moves with
/// the transform), its surfaces at `surfaces_rad` (aileron, elevator, rudder).
pub fn aircraft_scene(buffer: &mut ProtoBuffer, wall_ns: u64, surfaces_rad: [f64; 3]) {
    buffer.start();
    buffer.begin(2); // entities
    buffer.timestamp(1, wall_ns);
    buffer.string(2, BODY_FRAME);
    buffer.string(3, ENTITY_ID);
    buffer.int(5, 1); // frame_locked
    // Fuselage, then the nose: a cone (top_scale 0) pointing forward.
    for (center_x_m, length_m, top_scale) in [(-1.25, 11.5, 1.0), (6.0, 3.0, 0.0)] {
        buffer.begin(10); // cylinders
        buffer.pose([center_x_m, 0.0, 0.0], CYLINDER_ALONG_X);
        buffer.xyz(2, [1.3, 1.3, length_m]);
        buffer.double(3, 1.0);
        buffer.double(4, top_scale);
        buffer.xyzw(5, AIRFRAME);
        buffer.end();
    }
    for block in &BLOCKS {
        buffer.begin(8); // cubes
        buffer.pose(block.center_m, [0.0, 0.0, 0.0, 1.0]);
        buffer.xyz(2, block.size_m);
        buffer.xyzw(3, block.color);
        buffer.end();
    }
    for s in &SURFACES {
        let (center, orientation) = s.pose(surfaces_rad);
        buffer.begin(8);
        buffer.pose(center, orientation);
        buffer.xyz(2, s.size_m);
        buffer.xyzw(3, SURFACE);
        buffer.end();
    }
    buffer.end();
}

/// Protobuf field types and labels used by the schemas (`google.protobuf.FieldDescriptorProto`).
const DOUBLE: u8 = 1;
const INT64: u8 = 3;
const INT32: u8 = 5;
const FIXED32: u8 = 7;
const BOOL: u8 = 8;
const STRING: u8 = 9;
const MESSAGE: u8 = 11;
const BYTES: u8 = 12;
const ENUM: u8 = 14;
const OPTIONAL: u8 = 1;
const REPEATED: u8 = 3;

/// A field: name, number, label, type, type name (`.package.Message` for messages and enums, else empty).
type Field = (&'static str, u32, u8, u8, &'static str);
/// A message: name, fields, nested enums (name, values).
type Message = (&'static str, &'static [Field], &'static [(&'static str, &'static [(&'static str, i64)])]);
/// A `.proto` file: name, package, dependencies, its one message.
type ProtoFile = (&'static str, &'static str, &'static [&'static str], Message);

/// Foxglove's schemas for the two messages and every type they use, as `foxglove-schemas-protobuf` has them.
const FILES: [ProtoFile; 20] = [
    (
        "google/protobuf/timestamp.proto",
        "google.protobuf",
        &[],
        ("Timestamp", &[("seconds", 1, OPTIONAL, INT64, ""), ("nanos", 2, OPTIONAL, INT32, "")], &[]),
    ),
    (
        "google/protobuf/duration.proto",
        "google.protobuf",
        &[],
        ("Duration", &[("seconds", 1, OPTIONAL, INT64, ""), ("nanos", 2, OPTIONAL, INT32, "")], &[]),
    ),
    (
        "foxglove/Vector3.proto",
        "foxglove",
        &[],
        (
            "Vector3",
            &[("x", 1, OPTIONAL, DOUBLE, ""), ("y", 2, OPTIONAL, DOUBLE, ""), ("z", 3, OPTIONAL, DOUBLE, "")],
            &[],
        ),
    ),
    (
        "foxglove/Point3.proto",
        "foxglove",
        &[],
        (
            "Point3",
            &[("x", 1, OPTIONAL, DOUBLE, ""), ("y", 2, OPTIONAL, DOUBLE, ""), ("z", 3, OPTIONAL, DOUBLE, "")],
            &[],
        ),
    ),
    (
        "foxglove/Quaternion.proto",
        "foxglove",
        &[],
        (
            "Quaternion",
            &[
                ("x", 1, OPTIONAL, DOUBLE, ""),
                ("y", 2, OPTIONAL, DOUBLE, ""),
                ("z", 3, OPTIONAL, DOUBLE, ""),
                ("w", 4, OPTIONAL, DOUBLE, ""),
            ],
            &[],
        ),
    ),
    (
        "foxglove/Color.proto",
        "foxglove",
        &[],
        (
            "Color",
            &[
                ("r", 1, OPTIONAL, DOUBLE, ""),
                ("g", 2, OPTIONAL, DOUBLE, ""),
                ("b", 3, OPTIONAL, DOUBLE, ""),
                ("a", 4, OPTIONAL, DOUBLE, ""),
            ],
            &[],
        ),
    ),
    (
        "foxglove/KeyValuePair.proto",
        "foxglove",
        &[],
        ("KeyValuePair", &[("key", 1, OPTIONAL, STRING, ""), ("value", 2, OPTIONAL, STRING, "")], &[]),
    ),
    (
        "foxglove/Pose.proto",
        "foxglove",
        &["foxglove/Quaternion.proto", "foxglove/Vector3.proto"],
        (
            "Pose",
            &[
                ("position", 1, OPTIONAL, MESSAGE, ".foxglove.Vector3"),
                ("orientation", 2, OPTIONAL, MESSAGE, ".foxglove.Quaternion"),
            ],
            &[],
        ),
    ),
    (
        "foxglove/FrameTransform.proto",
        "foxglove",
        &["foxglove/Quaternion.proto", "foxglove/Vector3.proto", "google/protobuf/timestamp.proto"],
        (
            "FrameTransform",
            &[
                ("timestamp", 1, OPTIONAL, MESSAGE, ".google.protobuf.Timestamp"),
                ("parent_frame_id", 2, OPTIONAL, STRING, ""),
                ("child_frame_id", 3, OPTIONAL, STRING, ""),
                ("translation", 4, OPTIONAL, MESSAGE, ".foxglove.Vector3"),
                ("rotation", 5, OPTIONAL, MESSAGE, ".foxglove.Quaternion"),
            ],
            &[],
        ),
    ),
    (
        "foxglove/ArrowPrimitive.proto",
        "foxglove",
        &["foxglove/Color.proto", "foxglove/Pose.proto"],
        (
            "ArrowPrimitive",
            &[
                ("pose", 1, OPTIONAL, MESSAGE, ".foxglove.Pose"),
                ("shaft_length", 2, OPTIONAL, DOUBLE, ""),
                ("shaft_diameter", 3, OPTIONAL, DOUBLE, ""),
                ("head_length", 4, OPTIONAL, DOUBLE, ""),
                ("head_diameter", 5, OPTIONAL, DOUBLE, ""),
                ("color", 6, OPTIONAL, MESSAGE, ".foxglove.Color"),
            ],
            &[],
        ),
    ),
    (
        "foxglove/CubePrimitive.proto",
        "foxglove",
        &["foxglove/Color.proto", "foxglove/Pose.proto", "foxglove/Vector3.proto"],
        (
            "CubePrimitive",
            &[
                ("pose", 1, OPTIONAL, MESSAGE, ".foxglove.Pose"),
                ("size", 2, OPTIONAL, MESSAGE, ".foxglove.Vector3"),
                ("color", 3, OPTIONAL, MESSAGE, ".foxglove.Color"),
            ],
            &[],
        ),
    ),
    (
        "foxglove/SpherePrimitive.proto",
        "foxglove",
        &["foxglove/Color.proto", "foxglove/Pose.proto", "foxglove/Vector3.proto"],
        (
            "SpherePrimitive",
            &[
                ("pose", 1, OPTIONAL, MESSAGE, ".foxglove.Pose"),
                ("size", 2, OPTIONAL, MESSAGE, ".foxglove.Vector3"),
                ("color", 3, OPTIONAL, MESSAGE, ".foxglove.Color"),
            ],
            &[],
        ),
    ),
    (
        "foxglove/CylinderPrimitive.proto",
        "foxglove",
        &["foxglove/Color.proto", "foxglove/Pose.proto", "foxglove/Vector3.proto"],
        (
            "CylinderPrimitive",
            &[
                ("pose", 1, OPTIONAL, MESSAGE, ".foxglove.Pose"),
                ("size", 2, OPTIONAL, MESSAGE, ".foxglove.Vector3"),
                ("bottom_scale", 3, OPTIONAL, DOUBLE, ""),
                ("top_scale", 4, OPTIONAL, DOUBLE, ""),
                ("color", 5, OPTIONAL, MESSAGE, ".foxglove.Color"),
            ],
            &[],
        ),
    ),
    (
        "foxglove/LinePrimitive.proto",
        "foxglove",
        &["foxglove/Color.proto", "foxglove/Point3.proto", "foxglove/Pose.proto"],
        (
            "LinePrimitive",
            &[
                ("type", 1, OPTIONAL, ENUM, ".foxglove.LinePrimitive.Type"),
                ("pose", 2, OPTIONAL, MESSAGE, ".foxglove.Pose"),
                ("thickness", 3, OPTIONAL, DOUBLE, ""),
                ("scale_invariant", 4, OPTIONAL, BOOL, ""),
                ("points", 5, REPEATED, MESSAGE, ".foxglove.Point3"),
                ("color", 6, OPTIONAL, MESSAGE, ".foxglove.Color"),
                ("colors", 7, REPEATED, MESSAGE, ".foxglove.Color"),
                ("indices", 8, REPEATED, FIXED32, ""),
            ],
            &[("Type", &[("LINE_STRIP", 0), ("LINE_LOOP", 1), ("LINE_LIST", 2)])],
        ),
    ),
    (
        "foxglove/TriangleListPrimitive.proto",
        "foxglove",
        &["foxglove/Color.proto", "foxglove/Point3.proto", "foxglove/Pose.proto"],
        (
            "TriangleListPrimitive",
            &[
                ("pose", 1, OPTIONAL, MESSAGE, ".foxglove.Pose"),
                ("points", 2, REPEATED, MESSAGE, ".foxglove.Point3"),
                ("color", 3, OPTIONAL, MESSAGE, ".foxglove.Color"),
                ("colors", 4, REPEATED, MESSAGE, ".foxglove.Color"),
                ("indices", 5, REPEATED, FIXED32, ""),
            ],
            &[],
        ),
    ),
    (
        "foxglove/TextPrimitive.proto",
        "foxglove",
        &["foxglove/Color.proto", "foxglove/Pose.proto"],
        (
            "TextPrimitive",
            &[
                ("pose", 1, OPTIONAL, MESSAGE, ".foxglove.Pose"),
                ("billboard", 2, OPTIONAL, BOOL, ""),
                ("font_size", 3, OPTIONAL, DOUBLE, ""),
                ("scale_invariant", 4, OPTIONAL, BOOL, ""),
                ("color", 5, OPTIONAL, MESSAGE, ".foxglove.Color"),
                ("text", 6, OPTIONAL, STRING, ""),
            ],
            &[],
        ),
    ),
    (
        "foxglove/ModelPrimitive.proto",
        "foxglove",
        &["foxglove/Color.proto", "foxglove/Pose.proto", "foxglove/Vector3.proto"],
        (
            "ModelPrimitive",
            &[
                ("pose", 1, OPTIONAL, MESSAGE, ".foxglove.Pose"),
                ("scale", 2, OPTIONAL, MESSAGE, ".foxglove.Vector3"),
                ("color", 3, OPTIONAL, MESSAGE, ".foxglove.Color"),
                ("override_color", 4, OPTIONAL, BOOL, ""),
                ("url", 5, OPTIONAL, STRING, ""),
                ("media_type", 6, OPTIONAL, STRING, ""),
                ("data", 7, OPTIONAL, BYTES, ""),
            ],
            &[],
        ),
    ),
    (
        "foxglove/SceneEntity.proto",
        "foxglove",
        &[
            "foxglove/ArrowPrimitive.proto",
            "foxglove/CubePrimitive.proto",
            "foxglove/CylinderPrimitive.proto",
            "foxglove/KeyValuePair.proto",
            "foxglove/LinePrimitive.proto",
            "foxglove/ModelPrimitive.proto",
            "foxglove/SpherePrimitive.proto",
            "foxglove/TextPrimitive.proto",
            "foxglove/TriangleListPrimitive.proto",
            "google/protobuf/duration.proto",
            "google/protobuf/timestamp.proto",
        ],
        (
            "SceneEntity",
            &[
                ("timestamp", 1, OPTIONAL, MESSAGE, ".google.protobuf.Timestamp"),
                ("frame_id", 2, OPTIONAL, STRING, ""),
                ("id", 3, OPTIONAL, STRING, ""),
                ("lifetime", 4, OPTIONAL, MESSAGE, ".google.protobuf.Duration"),
                ("frame_locked", 5, OPTIONAL, BOOL, ""),
                ("metadata", 6, REPEATED, MESSAGE, ".foxglove.KeyValuePair"),
                ("arrows", 7, REPEATED, MESSAGE, ".foxglove.ArrowPrimitive"),
                ("cubes", 8, REPEATED, MESSAGE, ".foxglove.CubePrimitive"),
                ("spheres", 9, REPEATED, MESSAGE, ".foxglove.SpherePrimitive"),
                ("cylinders", 10, REPEATED, MESSAGE, ".foxglove.CylinderPrimitive"),
                ("lines", 11, REPEATED, MESSAGE, ".foxglove.LinePrimitive"),
                ("triangles", 12, REPEATED, MESSAGE, ".foxglove.TriangleListPrimitive"),
                ("texts", 13, REPEATED, MESSAGE, ".foxglove.TextPrimitive"),
                ("models", 14, REPEATED, MESSAGE, ".foxglove.ModelPrimitive"),
            ],
            &[],
        ),
    ),
    (
        "foxglove/SceneEntityDeletion.proto",
        "foxglove",
        &["google/protobuf/timestamp.proto"],
        (
            "SceneEntityDeletion",
            &[
                ("timestamp", 1, OPTIONAL, MESSAGE, ".google.protobuf.Timestamp"),
                ("type", 2, OPTIONAL, ENUM, ".foxglove.SceneEntityDeletion.Type"),
                ("id", 3, OPTIONAL, STRING, ""),
            ],
            &[("Type", &[("MATCHING_ID", 0), ("ALL", 1)])],
        ),
    ),
    (
        "foxglove/SceneUpdate.proto",
        "foxglove",
        &["foxglove/SceneEntity.proto", "foxglove/SceneEntityDeletion.proto"],
        (
            "SceneUpdate",
            &[
                ("deletions", 1, REPEATED, MESSAGE, ".foxglove.SceneEntityDeletion"),
                ("entities", 2, REPEATED, MESSAGE, ".foxglove.SceneEntity"),
            ],
            &[],
        ),
    ),
];

/// The `google.protobuf.FileDescriptorSet` of schema `name` (`foxglove.FrameTransform`, `foxglove.SceneUpdate`):
/// its file and every file it imports, each after its imports, as Foxglove reads an MCAP schema's data.
pub fn descriptor_set(name: &str) -> Vec<u8> {
    fn add(file: &str, order: &mut Vec<&'static ProtoFile>) {
        let f = FILES.iter().find(|f| f.0 == file).expect("a schema file of the table");
        if order.iter().any(|o| o.0 == file) {
            return;
        }
        for dep in f.2 {
            add(dep, order);
        }
        order.push(f);
    }
    let short = name.strip_prefix("foxglove.").expect("a foxglove schema");
    let mut order = Vec::new();
    add(&format!("foxglove/{short}.proto"), &mut order);
    let mut b = ProtoBuffer::default();
    for (file, package, deps, (message, fields, enums)) in order {
        b.begin(1); // FileDescriptorSet.file
        b.string(1, file);
        b.string(2, package);
        for dep in *deps {
            b.string(3, dep);
        }
        b.begin(4); // message_type
        b.string(1, message);
        for (field, number, label, ty, type_name) in *fields {
            b.begin(2);
            b.string(1, field);
            b.int(3, i64::from(*number));
            b.int(4, i64::from(*label));
            b.int(5, i64::from(*ty));
            if !type_name.is_empty() {
                b.string(6, type_name);
            }
            b.end();
        }
        for (enum_name, values) in *enums {
            b.begin(4); // enum_type
            b.string(1, enum_name);
            for (value, number) in *values {
                b.begin(2);
                b.string(1, value);
                b.int(2, *number);
                b.end();
            }
            b.end();
        }
        b.end();
        b.string(12, "proto3");
        b.end();
    }
    b.bytes
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f64::consts::FRAC_PI_2;

    /// A rotation's matrix, to compare frames by the axes they map.
    fn matrix([x, y, z, w]: [f64; 4]) -> [[f64; 3]; 3] {
        [
            [1.0 - 2.0 * (y * y + z * z), 2.0 * (x * y - z * w), 2.0 * (x * z + y * w)],
            [2.0 * (x * y + z * w), 1.0 - 2.0 * (x * x + z * z), 2.0 * (y * z - x * w)],
            [2.0 * (x * z - y * w), 2.0 * (y * z + x * w), 1.0 - 2.0 * (x * x + y * y)],
        ]
    }

    fn column(q: [f64; 4], k: usize) -> [f64; 3] {
        let m = matrix(q);
        [m[0][k], m[1][k], m[2][k]]
    }

    fn close(a: [f64; 3], b: [f64; 3]) -> bool {
        a.iter().zip(b).all(|(x, y)| (x - y).abs() < 1e-12)
    }

    #[test]
    fn the_nose_points_along_the_heading_and_the_right_wing_drops_in_a_right_roll() {
        // Level, heading north: nose north (+y in ENU), left wing west (-x), up up.
        let q = enu_flu_quaternion(0.0, 0.0, 0.0);
        assert!(close(column(q, 0), [0.0, 1.0, 0.0]) && close(column(q, 1), [-1.0, 0.0, 0.0]));
        // Heading east.
        assert!(close(column(enu_flu_quaternion(0.0, 0.0, FRAC_PI_2), 0), [1.0, 0.0, 0.0]));
        // Nose up 90 degrees.
        assert!(close(column(enu_flu_quaternion(0.0, FRAC_PI_2, 0.0), 0), [0.0, 0.0, 1.0]));
        // Right roll 90 degrees, heading north: the left wing points up.
        assert!(close(column(enu_flu_quaternion(FRAC_PI_2, 0.0, 0.0), 1), [0.0, 0.0, 1.0]));
    }

    #[test]
    fn nested_lengths_take_as_many_bytes_as_they_need() {
        let mut b = ProtoBuffer::default();
        b.start();
        b.begin(2);
        b.string(1, &"x".repeat(200));
        b.end();
        // key, 2-byte length 203, key, 2-byte length 200, the text.
        assert_eq!(&b.bytes()[..6], &[0x12, 0xcb, 0x01, 0x0a, 0xc8, 0x01]);
        assert_eq!(b.bytes().len(), 206);
    }

    #[test]
    fn a_deflected_trailing_edge_goes_down_and_left() {
        let mut b = ProtoBuffer::default();
        aircraft_scene(&mut b, 0, [0.1, 0.1, 0.1]);
        let neutral = {
            let mut n = ProtoBuffer::default();
            aircraft_scene(&mut n, 0, [0.0; 3]);
            n.bytes
        };
        assert_eq!(b.bytes().len(), neutral.len(), "a deflection changes values, not the message's shape");
        assert_ne!(b.bytes(), &neutral[..]);
        // Each surface's centre lies behind its hinge, so it follows the trailing edge: a positive deflection moves
        // the right aileron's and the tail's down, the left aileron's up, the rudder's left (+y).
        let moved = |k: usize| {
            let s = &SURFACES[k];
            let (at, _) = s.pose([0.1; 3]);
            [at[0] - s.hinge_m[0], at[1] - s.hinge_m[1], at[2] - s.hinge_m[2]]
        };
        assert!(moved(0)[2] < 0.0 && moved(1)[2] > 0.0 && moved(2)[2] < 0.0 && moved(3)[2] < 0.0);
        assert!(moved(4)[1] > 0.0 && moved(4)[2] == 0.0);
        // The orientation turns the box the same way as its centre: its +x axis (toward the leading edge) up.
        let (_, q) = SURFACES[0].pose([0.1; 3]);
        assert!(column(q, 0)[2] > 0.0);
    }

    #[test]
    fn every_schema_file_is_in_the_table_once() {
        for (k, f) in FILES.iter().enumerate() {
            assert!(FILES[k + 1..].iter().all(|g| g.0 != f.0), "{} twice", f.0);
            for dep in f.2 {
                assert!(FILES.iter().any(|g| g.0 == *dep), "{} imports {dep}, not in the table", f.0);
            }
        }
        assert!(!descriptor_set(FRAME_TRANSFORM).is_empty() && !descriptor_set(SCENE_UPDATE).is_empty());
    }
}
