//! The aircraft in 3-D for Foxglove's 3D panel: a plant's position and attitude as a `foxglove.FrameTransform`
//! (parent `world`, child `body`) and a simple aircraft of primitives with its control surfaces deflected as a
//! `foxglove.SceneUpdate` in `body`, both protobuf-encoded, with the `FileDescriptorSet` Foxglove decodes them by
//! ([`descriptor_set`]). The messages, their encoding and their schemas are the `foxglove` crate's (the Foxglove
//! SDK's, without its features): they cost the logger 0.04 MB and a clean build about 4 % more CPU
//! (docs/src/explanations/architecture.md, "Written by hand, held to others' tests"), where our own encoding was 400
//! lines more.
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

use foxglove::Encode;
use foxglove::schemas::{
    Color, CubePrimitive, CylinderPrimitive, FrameTransform, Pose, Quaternion, SceneEntity, SceneUpdate, Timestamp,
    Vector3,
};
use silrig_flight::signals::PlantSignals;
use silrig_model::quad::rotors::{ROTOR_POSITION, ROTORS};

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
    /// The four rotor speeds' output indices (`omega1_radps` .. `omega4_radps`), when announced: drawn as an X
    /// quadrotor.
    rotors: Option<[usize; ROTORS]>,
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
        let rotors: Option<Vec<usize>> = (1..=ROTORS).map(|k| plant.output(&format!("omega{k}_radps")).ok()).collect();
        let rotors = rotors.and_then(|r| r.try_into().ok());
        Some(Self { position, attitude, surfaces, rotors })
    }

    /// Whether the plant is drawn as an X quadrotor (it announces four rotor speeds) rather than the aircraft.
    pub fn rotorcraft(&self) -> bool {
        self.rotors.is_some()
    }

    /// Whether the plant announces any of the aircraft's surface positions.
    pub fn has_surfaces(&self) -> bool {
        self.surfaces.iter().any(Option::is_some)
    }

    /// The four rotor speeds, rad/s, in motor order, when the plant announces them.
    pub fn rotor_speeds_radps(&self, outputs: &[f64]) -> Option<[f64; ROTORS]> {
        self.rotors.map(|rotors| rotors.map(|k| outputs[k]))
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

/// The 3-D messages, built once and changed in place, and the bytes of the last one encoded: encoding one allocates
/// nothing once the buffer has grown (the logger writes a transform every row).
#[derive(Debug)]
pub struct ProtoBuffer {
    bytes: Vec<u8>,
    transform: FrameTransform,
    scene: SceneUpdate,
    /// The moving surfaces of the model drawn, whose cubes follow the scene's fixed blocks (none: the quadrotor).
    surfaces: &'static [Surface],
}

impl Default for ProtoBuffer {
    fn default() -> Self {
        let transform = FrameTransform {
            parent_frame_id: WORLD_FRAME.into(),
            child_frame_id: BODY_FRAME.into(),
            ..Default::default()
        };
        let scene = SceneUpdate { deletions: Vec::new(), entities: vec![aircraft()] };
        Self { bytes: Vec::new(), transform, scene, surfaces: &SURFACES }
    }
}

impl ProtoBuffer {
    /// Draw an X quadrotor of arm `arm_m` (centre to rotor axis, m) from now on, or the aircraft again (`None`).
    pub fn draw(&mut self, rotorcraft_arm_m: Option<f64>) {
        self.scene.entities[0] = rotorcraft_arm_m.map_or_else(aircraft, quadrotor);
        self.surfaces = if rotorcraft_arm_m.is_some() { &[] } else { &SURFACES };
    }

    /// The message last encoded.
    pub fn bytes(&self) -> &[u8] {
        &self.bytes
    }
}

/// `message` encoded into `bytes`, replacing what was there.
fn encode(bytes: &mut Vec<u8>, message: &impl Encode) {
    bytes.clear();
    message.encode(bytes).expect("a Vec<u8> grows as the message needs");
}

/// Foxglove's timestamp: unsigned 32-bit seconds (to 2106) and nanoseconds.
fn timestamp(wall_ns: u64) -> Option<Timestamp> {
    Some(Timestamp::new((wall_ns / 1_000_000_000) as u32, (wall_ns % 1_000_000_000) as u32))
}

fn v3([x, y, z]: [f64; 3]) -> Option<Vector3> {
    Some(Vector3 { x, y, z })
}

fn quat([x, y, z, w]: [f64; 4]) -> Option<Quaternion> {
    Some(Quaternion { x, y, z, w })
}

fn color([r, g, b, a]: [f64; 4]) -> Option<Color> {
    Some(Color { r, g, b, a })
}

fn pose(position_m: [f64; 3], orientation: [f64; 4]) -> Option<Pose> {
    Some(Pose { position: v3(position_m), orientation: quat(orientation) })
}

/// A `foxglove.FrameTransform` world -> body at `wall_ns` into `buffer`.
pub fn frame_transform(buffer: &mut ProtoBuffer, wall_ns: u64, translation_m: [f64; 3], rotation: [f64; 4]) {
    let t = &mut buffer.transform;
    (t.timestamp, t.translation, t.rotation) = (timestamp(wall_ns), v3(translation_m), quat(rotation));
    encode(&mut buffer.bytes, &buffer.transform);
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
#[derive(Debug, Clone, Copy)]
enum Hinge {
    Y,
    Z,
}

/// A moving surface: a box hinged on a line through `hinge_m` along its axis, its centre `center_aft_m` behind the
/// hinge; it turns by `sign` times a surface's position (index into aileron, elevator, rudder).
#[derive(Debug)]
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

/// The aircraft in `body` (frame-locked, so it moves with the transform), its surfaces neutral: the fuselage and the
/// nose (a cone: top scale 0) pointing forward, the fixed blocks, then the moving surfaces.
fn aircraft() -> SceneEntity {
    let cylinders = [(-1.25, 11.5, 1.0), (6.0, 3.0, 0.0)].map(|(center_x_m, length_m, top_scale)| CylinderPrimitive {
        pose: pose([center_x_m, 0.0, 0.0], CYLINDER_ALONG_X),
        size: v3([1.3, 1.3, length_m]),
        bottom_scale: 1.0,
        top_scale,
        color: color(AIRFRAME),
    });
    let blocks = BLOCKS.iter().map(|b| CubePrimitive {
        pose: pose(b.center_m, [0.0, 0.0, 0.0, 1.0]),
        size: v3(b.size_m),
        color: color(b.color),
    });
    let surfaces = SURFACES.iter().map(|s| {
        let (center, orientation) = s.pose([0.0; 3]);
        CubePrimitive { pose: pose(center, orientation), size: v3(s.size_m), color: color(SURFACE) }
    });
    SceneEntity {
        frame_id: BODY_FRAME.into(),
        id: ENTITY_ID.into(),
        frame_locked: true,
        cubes: blocks.chain(surfaces).collect(),
        cylinders: cylinders.to_vec(),
        ..Default::default()
    }
}

/// The aircraft as the run page's 3-D view draws it (src/tools/html/view3d.js), the same parts as [`aircraft`]:
/// cylinders along the body's x (centre, length, diameter, top scale: 0 a cone), the fixed boxes and the moving
/// surfaces with their hinges (axis 0 is the body's y, 1 its z), m in `body`, colours r, g, b.
pub fn aircraft_model() -> serde_json::Value {
    use serde_json::json;
    let rgb = |c: [f64; 4]| [c[0], c[1], c[2]];
    let entity = aircraft();
    let cylinders: Vec<_> = entity
        .cylinders
        .iter()
        .map(|c| {
            let (pose, size) = (c.pose.as_ref().and_then(|p| p.position.as_ref()), c.size.as_ref());
            json!({
                "x": pose.map_or(0.0, |p| p.x),
                "length": size.map_or(0.0, |s| s.z),
                "diameter": size.map_or(0.0, |s| s.x),
                "top": c.top_scale,
                "color": rgb(AIRFRAME),
            })
        })
        .collect();
    let boxes: Vec<_> =
        BLOCKS.iter().map(|b| json!({"center": b.center_m, "size": b.size_m, "color": rgb(b.color)})).collect();
    let surfaces: Vec<_> = SURFACES
        .iter()
        .map(|s| {
            json!({
                "surface": s.surface,
                "sign": s.sign,
                "axis": match s.axis { Hinge::Y => 0, Hinge::Z => 1 },
                "hinge": s.hinge_m,
                "aft": s.center_aft_m,
                "size": s.size_m,
                "color": rgb(SURFACE),
            })
        })
        .collect();
    json!({"kind": "aircraft", "length_m": 15.0, "cylinders": cylinders, "boxes": boxes, "surfaces": surfaces})
}

/// Each moving surface's box centre (m) and orientation (x, y, z, w) in `body` with the surfaces at `surfaces_rad`
/// (aileron, elevator, rudder): what the 3-D view's script must compute alike (tests/html_report.rs).
pub fn surface_poses(surfaces_rad: [f64; 3]) -> Vec<([f64; 3], [f64; 4])> {
    SURFACES.iter().map(|s| s.pose(surfaces_rad)).collect()
}

/// The quadrotor's colours: its frame, its nose, its rotor discs.
const FRAME: [f64; 4] = [0.35, 0.37, 0.4, 1.0];
const NOSE: [f64; 4] = [0.8, 0.1, 0.1, 1.0];
const ROTOR: [f64; 4] = [1.0, 0.45, 0.05, 0.8];

/// An X quadrotor in `body`, `arm_m` from its centre to each rotor's axis: a hub, a red block at the nose, two arms
/// across, and a disc for each rotor in motor order (Betaflight's Quad X, as the built-in quadrotor's), each 0.9
/// arm across.
fn quadrotor(arm_m: f64) -> SceneEntity {
    let along = arm_m / std::f64::consts::SQRT_2;
    let yaw = |deg: f64| [0.0, 0.0, (deg.to_radians() / 2.0).sin(), (deg.to_radians() / 2.0).cos()];
    let cube = |center: [f64; 3], q: [f64; 4], size: [f64; 3], c: [f64; 4]| CubePrimitive {
        pose: pose(center.map(|v| v * arm_m), q),
        size: v3(size.map(|v| v * arm_m)),
        color: color(c),
    };
    let cubes = vec![
        cube([0.0, 0.0, 0.0], yaw(0.0), [0.45, 0.35, 0.15], FRAME),
        cube([0.3, 0.0, 0.05], yaw(0.0), [0.2, 0.12, 0.1], NOSE),
        cube([0.0, 0.0, 0.0], yaw(45.0), [2.0, 0.08, 0.05], FRAME),
        cube([0.0, 0.0, 0.0], yaw(-45.0), [2.0, 0.08, 0.05], FRAME),
    ];
    // Motor order's (forward, right) to forward-left; a disc's axis is its frame's z, the body's up.
    let cylinders = ROTOR_POSITION
        .iter()
        .map(|[x, y]| CylinderPrimitive {
            pose: pose([x * along, -y * along, 0.03 * arm_m], [0.0, 0.0, 0.0, 1.0]),
            size: v3([0.9 * arm_m, 0.9 * arm_m, 0.02 * arm_m]),
            bottom_scale: 1.0,
            top_scale: 1.0,
            color: color(ROTOR),
        })
        .collect();
    SceneEntity {
        frame_id: BODY_FRAME.into(),
        id: ENTITY_ID.into(),
        frame_locked: true,
        cubes,
        cylinders,
        ..Default::default()
    }
}

/// The arm a quadrotor is drawn with, m: the scenario's `[plant.parameters] arm_m` (TOML), else the built-in
/// quadrotor's.
pub fn rotor_arm_m(scenario_toml: &str) -> f64 {
    silrig_flight::scenario::Scenario::from_toml(scenario_toml, "the recording's scenario")
        .ok()
        .and_then(|s| s.plant.parameters.get("arm_m").copied())
        .unwrap_or(silrig_model::quad::params::QuadParams::default().arm_m)
}

/// The quadrotor as the run page's 3-D view draws it, the same parts as Foxglove's ([`quadrotor`]): boxes (centre,
/// orientation, size) and rotor discs (centre, diameter) in motor order, m in `body`, colours r, g, b.
pub fn quadrotor_model(arm_m: f64) -> serde_json::Value {
    use serde_json::json;
    let entity = quadrotor(arm_m);
    let position =
        |p: &Option<Pose>| p.as_ref().and_then(|p| p.position.as_ref()).map_or([0.0; 3], |v| [v.x, v.y, v.z]);
    let orientation = |p: &Option<Pose>| {
        p.as_ref().and_then(|p| p.orientation.as_ref()).map_or([0.0, 0.0, 0.0, 1.0], |q| [q.x, q.y, q.z, q.w])
    };
    let size = |s: &Option<Vector3>| s.as_ref().map_or([0.0; 3], |s| [s.x, s.y, s.z]);
    let rgb = |c: &Option<Color>| c.as_ref().map_or([0.0; 3], |c| [c.r, c.g, c.b]);
    let boxes: Vec<_> = entity
        .cubes
        .iter()
        .map(|c| json!({"center": position(&c.pose), "q": orientation(&c.pose), "size": size(&c.size), "color": rgb(&c.color)}))
        .collect();
    let rotors: Vec<_> =
        entity.cylinders.iter().map(|c| json!({"center": position(&c.pose), "diameter": size(&c.size)[0]})).collect();
    json!({"kind": "quadrotor", "length_m": 2.6 * arm_m, "boxes": boxes, "rotors": rotors})
}

/// A `foxglove.SceneUpdate` at `wall_ns` into `buffer`: the aircraft, its surfaces at `surfaces_rad` (aileron,
/// elevator, rudder).
pub fn aircraft_scene(buffer: &mut ProtoBuffer, wall_ns: u64, surfaces_rad: [f64; 3]) {
    let entity = &mut buffer.scene.entities[0];
    entity.timestamp = timestamp(wall_ns);
    for (cube, s) in entity.cubes[BLOCKS.len()..].iter_mut().zip(buffer.surfaces) {
        let (center, orientation) = s.pose(surfaces_rad);
        cube.pose = pose(center, orientation);
    }
    encode(&mut buffer.bytes, &buffer.scene);
}

/// The `FileDescriptorSet` of schema `name` (`foxglove.FrameTransform` or `foxglove.SceneUpdate`).
pub fn descriptor_set(name: &str) -> Vec<u8> {
    let schema = match name {
        FRAME_TRANSFORM => FrameTransform::get_schema(),
        SCENE_UPDATE => SceneUpdate::get_schema(),
        other => panic!("no schema {other}"),
    };
    schema.expect("a foxglove schema").data.into_owned()
}

#[cfg(test)]
mod tests {
    use super::*;
    use foxglove::Decode;
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
    fn a_deflected_trailing_edge_goes_down_and_left() {
        // The same buffer deflected, then neutral again: the surfaces move, nothing else does.
        let mut b = ProtoBuffer::default();
        let mut poses = |surfaces_rad: [f64; 3]| {
            aircraft_scene(&mut b, 0, surfaces_rad);
            let scene = SceneUpdate::decode(b.bytes()).unwrap();
            let cubes = scene.entities[0].cubes.iter().map(|c| c.pose).collect::<Vec<_>>();
            (cubes, scene.entities[0].cylinders.clone())
        };
        let (deflected, neutral) = (poses([0.1; 3]), poses([0.0; 3]));
        assert_eq!((&deflected.0[..BLOCKS.len()], &deflected.1), (&neutral.0[..BLOCKS.len()], &neutral.1));
        assert!(deflected.0[BLOCKS.len()..].iter().zip(&neutral.0[BLOCKS.len()..]).all(|(d, n)| d != n));
        assert_eq!(neutral.0, aircraft().cubes.iter().map(|c| c.pose).collect::<Vec<_>>());
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
    fn a_message_decodes_to_what_was_set_and_each_schema_is_its_descriptor_set() {
        let mut b = ProtoBuffer::default();
        frame_transform(&mut b, 3_000_000_007, [1.0, 2.0, 3.0], [0.0, 0.0, 0.6, 0.8]);
        let t = FrameTransform::decode(b.bytes()).unwrap();
        assert_eq!((t.parent_frame_id.as_str(), t.child_frame_id.as_str()), (WORLD_FRAME, BODY_FRAME));
        assert_eq!(t.timestamp, timestamp(3_000_000_007));
        assert_eq!((t.translation, t.rotation), (v3([1.0, 2.0, 3.0]), quat([0.0, 0.0, 0.6, 0.8])));
        aircraft_scene(&mut b, 5, [0.0, 0.2, 0.0]);
        let scene = SceneUpdate::decode(b.bytes()).unwrap();
        let entity = &scene.entities[0];
        assert_eq!((entity.id.as_str(), entity.frame_id.as_str(), entity.frame_locked), (ENTITY_ID, BODY_FRAME, true));
        assert_eq!((entity.cubes.len(), entity.cylinders.len()), (BLOCKS.len() + SURFACES.len(), 2));
        // The elevator's halves (surfaces 2 and 3) turned, the ailerons did not.
        let turned = |k: usize| entity.cubes[BLOCKS.len() + k].pose.unwrap().orientation.unwrap().y != 0.0;
        assert!(turned(2) && turned(3) && !turned(0) && !turned(4));
        for name in [FRAME_TRANSFORM, SCENE_UPDATE] {
            let data = descriptor_set(name);
            let set = <prost_types::FileDescriptorSet as prost::Message>::decode(&data[..]).unwrap();
            let short = name.trim_start_matches("foxglove.");
            assert!(set.file.iter().any(|f| f.message_type.iter().any(|m| m.name() == short)), "{name}");
        }
    }
}
