//! The feature vocabulary: one versioned registry of feature curves and
//! feature points, shared by bodies, templates and the API (seed 000 §3.1:
//! "each semantic feature point is an intersection point of two semantic
//! feature curves, and every semantic feature point has its own ID").
//!
//! IDs are stable snake_case strings; names follow ISO 8559-1:2017
//! ("Size designation of clothes — Anthropometric definitions for body
//! measurement") where it defines the landmark or girth.
//!
//! Each curve also carries the rule that derives it from landmark
//! positions on any body mesh (see [`crate::body::derive`]):
//! * a **section** is the closed loop cut by a plane through its landmarks
//!   (best-fit plane, horizontal plane, or the plane through two landmarks
//!   that contains a body axis);
//! * a **path** runs through its landmarks in order; between consecutive
//!   landmarks `p_i`, `p_{i+1}` it follows the section of the plane with
//!   normal `(p_{i+1} − p_i) × d`, `d` the depth axis named by the rule
//!   (Z, front–back, for centre lines; X, lateral, for side lines).
//!
//! Body axes: metres, Y up, the body faces +Z, so the body's left is +X.

use std::fmt;
use std::str::FromStr;

use glam::DVec3;
use serde::{Deserialize, Deserializer, Serialize, Serializer};

/// Version of this registry. Bump when an ID is added, removed or changes
/// meaning; templates and landmark files record the version they use.
/// Version 2 added the inner (medial) thigh, knee and ankle points, the
/// oblique torso points, the leg front/back points, and the lines that
/// define them. Version 3 added the arms (issue #18 item 5: what a sleeve
/// needs): the upper-arm, elbow and wrist girths, the shoulder-to-wrist
/// line and their points — [`ARM_CURVES`], derived where their landmarks
/// are given ([`optional_curve`]).
pub const VOCABULARY_VERSION: u32 = 3;

macro_rules! id_enum {
    ($(#[$doc:meta])* $name:ident { $($(#[$vdoc:meta])* $var:ident = $s:literal),+ $(,)? }) => {
        $(#[$doc])*
        #[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash)]
        pub enum $name { $($(#[$vdoc])* $var),+ }
        impl $name {
            /// Every ID, in registry order.
            pub const ALL: &'static [$name] = &[$($name::$var),+];
            /// The stable string ID.
            pub fn as_str(self) -> &'static str {
                match self { $($name::$var => $s),+ }
            }
        }
        impl fmt::Display for $name {
            fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result { f.write_str(self.as_str()) }
        }
        impl FromStr for $name {
            type Err = UnknownId;
            fn from_str(s: &str) -> Result<Self, UnknownId> {
                match s { $($s => Ok($name::$var),)+ _ => Err(UnknownId { kind: stringify!($name), id: s.to_owned() }) }
            }
        }
        impl utoipa::PartialSchema for $name {
            fn schema() -> utoipa::openapi::RefOr<utoipa::openapi::schema::Schema> {
                utoipa::openapi::ObjectBuilder::new()
                    .schema_type(utoipa::openapi::schema::Type::String)
                    .description(Some(concat!("A ", stringify!($name), " of the feature vocabulary")))
                    .enum_values(Some(Self::ALL.iter().map(|v| v.as_str())))
                    .into()
            }
        }
        impl utoipa::ToSchema for $name {}
        impl Serialize for $name {
            fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> { s.serialize_str(self.as_str()) }
        }
        impl<'de> Deserialize<'de> for $name {
            fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
                let s = String::deserialize(d)?;
                s.parse().map_err(serde::de::Error::custom)
            }
        }
    };
}

/// An ID that the vocabulary does not know.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("unknown {kind} `{id}` (vocabulary version {VOCABULARY_VERSION})")]
pub struct UnknownId {
    /// Which kind of ID (`PointId`, `CurveId`, …).
    pub kind: &'static str,
    /// The string that was given.
    pub id: String,
}

id_enum! {
    /// A feature curve.
    CurveId {
        /// Neck base girth (ISO 8559-1 5.3.2): through the cervicale, the side neck points and the front neck point.
        NeckBase = "neck_base",
        /// Chest girth at armpit level (ISO 8559-1 5.3.4), under the arms.
        Chest = "chest",
        /// Bust girth (ISO 8559-1 5.3.5), horizontal over the bust points.
        Bust = "bust",
        /// Underbust girth (ISO 8559-1 5.3.6).
        Underbust = "underbust",
        /// Waist girth (ISO 8559-1 5.3.10), at the natural waist.
        Waist = "waist",
        /// Hip girth (ISO 8559-1 5.3.13), at the greatest buttock prominence.
        Hip = "hip",
        /// Left thigh girth (ISO 8559-1 5.3.20), just below the gluteal fold.
        ThighLeft = "thigh_left",
        /// Right thigh girth.
        ThighRight = "thigh_right",
        /// Left knee girth (ISO 8559-1 5.3.22).
        KneeLeft = "knee_left",
        /// Right knee girth.
        KneeRight = "knee_right",
        /// Left ankle girth (ISO 8559-1 5.3.24).
        AnkleLeft = "ankle_left",
        /// Right ankle girth.
        AnkleRight = "ankle_right",
        /// Left armscye (armhole) girth (ISO 8559-1 5.3.15): through the shoulder point and the armpit.
        ArmscyeLeft = "armscye_left",
        /// Right armscye girth.
        ArmscyeRight = "armscye_right",
        /// Centre front line: front neck point down the sagittal plane to the crotch.
        CentreFront = "centre_front",
        /// Centre back line: cervicale down the spine to the crotch.
        CentreBack = "centre_back",
        /// Left side line: armpit down the side of the torso and the outside of the leg to the ankle.
        SideLineLeft = "side_line_left",
        /// Right side line.
        SideLineRight = "side_line_right",
        /// Left shoulder line: side neck point to shoulder point over the top of the shoulder.
        ShoulderLineLeft = "shoulder_line_left",
        /// Right shoulder line.
        ShoulderLineRight = "shoulder_line_right",
        /// Crotch line: the front-view (coronal) section through the crotch point.
        CrotchLine = "crotch_line",
        /// Left leg line: the coronal section at the mean depth of the left leg's side points; it runs down the
        /// outside and up the inside of the leg.
        LegLineLeft = "leg_line_left",
        /// Right leg line.
        LegLineRight = "leg_line_right",
        /// Oblique line through the front-left and back-right of the torso: the section of the vertical plane
        /// at 45° between the sagittal and coronal planes, through the waist's centre.
        ObliqueFrontLeft = "oblique_front_left",
        /// Oblique line through the front-right and back-left of the torso.
        ObliqueFrontRight = "oblique_front_right",
        /// Left leg sagittal line: the section of the sagittal plane through the mean of the left leg's girth
        /// points; it runs down the front and up the back of the leg.
        LegSagittalLeft = "leg_sagittal_left",
        /// Right leg sagittal line.
        LegSagittalRight = "leg_sagittal_right",
        /// Left upper-arm girth (ISO 8559-1 5.3.16): the arm's section perpendicular to the upper arm (shoulder
        /// point to elbow) through the upper-arm point, at the level of the armpit.
        UpperArmLeft = "upper_arm_left",
        /// Right upper-arm girth.
        UpperArmRight = "upper_arm_right",
        /// Left elbow girth (ISO 8559-1 5.3.17): the section through the elbow point perpendicular to the arm
        /// (shoulder point to wrist).
        ElbowLeft = "elbow_left",
        /// Right elbow girth.
        ElbowRight = "elbow_right",
        /// Left wrist girth (ISO 8559-1 5.3.19): the section through the wrist point perpendicular to the
        /// forearm (elbow to wrist).
        WristLeft = "wrist_left",
        /// Right wrist girth.
        WristRight = "wrist_right",
        /// Left arm line: shoulder point over the upper-arm point and the elbow to the wrist, down the outside
        /// of the arm (ISO 8559-1 5.4.14's arm length is its length); each piece in the plane of its chord and
        /// the vertical, which cuts the arm across its top (a plane of the chord and the depth axis would
        /// graze it along the top).
        ArmLineLeft = "arm_line_left",
        /// Right arm line.
        ArmLineRight = "arm_line_right",
    }
}

id_enum! {
    /// A feature point (also the landmark IDs accepted with a scan).
    PointId {
        /// Front neck point (ISO 8559-1 3.1.6).
        NeckFront = "neck_front",
        /// Back neck point, cervicale (ISO 8559-1 3.1.3).
        NeckBack = "neck_back",
        /// Left side neck point (ISO 8559-1 3.1.5).
        NeckLeft = "neck_left",
        /// Right side neck point.
        NeckRight = "neck_right",
        /// Left shoulder point, acromion (ISO 8559-1 3.1.1).
        ShoulderLeft = "shoulder_left",
        /// Right shoulder point.
        ShoulderRight = "shoulder_right",
        /// Left armpit point on the side line, at chest level (ISO 8559-1 3.1.11).
        UnderarmLeft = "underarm_left",
        /// Right armpit point.
        UnderarmRight = "underarm_right",
        /// Chest girth at centre front.
        ChestFront = "chest_front",
        /// Chest girth at centre back.
        ChestBack = "chest_back",
        /// Bust girth at centre front.
        BustFront = "bust_front",
        /// Bust girth at centre back.
        BustBack = "bust_back",
        /// Bust girth at the left side line.
        BustLeft = "bust_left",
        /// Bust girth at the right side line.
        BustRight = "bust_right",
        /// Underbust girth at centre front.
        UnderbustFront = "underbust_front",
        /// Underbust girth at centre back.
        UnderbustBack = "underbust_back",
        /// Underbust girth at the left side line.
        UnderbustLeft = "underbust_left",
        /// Underbust girth at the right side line.
        UnderbustRight = "underbust_right",
        /// Waist girth at centre front.
        WaistFront = "waist_front",
        /// Waist girth at centre back.
        WaistBack = "waist_back",
        /// Waist girth at the left side line.
        WaistLeft = "waist_left",
        /// Waist girth at the right side line.
        WaistRight = "waist_right",
        /// Hip girth at centre front.
        HipFront = "hip_front",
        /// Hip girth at centre back.
        HipBack = "hip_back",
        /// Hip girth at the left side line.
        HipLeft = "hip_left",
        /// Hip girth at the right side line.
        HipRight = "hip_right",
        /// Crotch point (ISO 8559-1 3.1.15).
        Crotch = "crotch",
        /// Left thigh girth at the side line.
        ThighLeft = "thigh_left",
        /// Right thigh girth at the side line.
        ThighRight = "thigh_right",
        /// Left knee girth at the side line.
        KneeLeft = "knee_left",
        /// Right knee girth at the side line.
        KneeRight = "knee_right",
        /// Left ankle girth at the side line.
        AnkleLeft = "ankle_left",
        /// Right ankle girth at the side line.
        AnkleRight = "ankle_right",
        /// Left thigh girth at the inside of the leg (crotch line crossing).
        ThighLeftInner = "thigh_left_inner",
        /// Right thigh girth at the inside of the leg.
        ThighRightInner = "thigh_right_inner",
        /// Left knee girth at the inside of the leg.
        KneeLeftInner = "knee_left_inner",
        /// Right knee girth at the inside of the leg.
        KneeRightInner = "knee_right_inner",
        /// Left ankle girth at the inside of the leg.
        AnkleLeftInner = "ankle_left_inner",
        /// Right ankle girth at the inside of the leg.
        AnkleRightInner = "ankle_right_inner",
        /// Neck base girth at the front-left oblique line.
        NeckFrontLeft = "neck_front_left",
        /// Neck base girth at the back-left oblique line.
        NeckBackLeft = "neck_back_left",
        /// Neck base girth at the back-right oblique line.
        NeckBackRight = "neck_back_right",
        /// Neck base girth at the front-right oblique line.
        NeckFrontRight = "neck_front_right",
        /// Chest girth at the front-left oblique line.
        ChestFrontLeft = "chest_front_left",
        /// Chest girth at the back-left oblique line.
        ChestBackLeft = "chest_back_left",
        /// Chest girth at the back-right oblique line.
        ChestBackRight = "chest_back_right",
        /// Chest girth at the front-right oblique line.
        ChestFrontRight = "chest_front_right",
        /// Bust girth at the front-left oblique line.
        BustFrontLeft = "bust_front_left",
        /// Bust girth at the back-left oblique line.
        BustBackLeft = "bust_back_left",
        /// Bust girth at the back-right oblique line.
        BustBackRight = "bust_back_right",
        /// Bust girth at the front-right oblique line.
        BustFrontRight = "bust_front_right",
        /// Underbust girth at the front-left oblique line.
        UnderbustFrontLeft = "underbust_front_left",
        /// Underbust girth at the back-left oblique line.
        UnderbustBackLeft = "underbust_back_left",
        /// Underbust girth at the back-right oblique line.
        UnderbustBackRight = "underbust_back_right",
        /// Underbust girth at the front-right oblique line.
        UnderbustFrontRight = "underbust_front_right",
        /// Waist girth at the front-left oblique line.
        WaistFrontLeft = "waist_front_left",
        /// Waist girth at the back-left oblique line.
        WaistBackLeft = "waist_back_left",
        /// Waist girth at the back-right oblique line.
        WaistBackRight = "waist_back_right",
        /// Waist girth at the front-right oblique line.
        WaistFrontRight = "waist_front_right",
        /// Hip girth at the front-left oblique line.
        HipFrontLeft = "hip_front_left",
        /// Hip girth at the back-left oblique line.
        HipBackLeft = "hip_back_left",
        /// Hip girth at the back-right oblique line.
        HipBackRight = "hip_back_right",
        /// Hip girth at the front-right oblique line.
        HipFrontRight = "hip_front_right",
        /// Left thigh girth at the front of the leg.
        ThighLeftFront = "thigh_left_front",
        /// Left thigh girth at the back of the leg.
        ThighLeftBack = "thigh_left_back",
        /// Right thigh girth at the front of the leg.
        ThighRightFront = "thigh_right_front",
        /// Right thigh girth at the back of the leg.
        ThighRightBack = "thigh_right_back",
        /// Left knee girth at the front of the leg.
        KneeLeftFront = "knee_left_front",
        /// Left knee girth at the back of the leg.
        KneeLeftBack = "knee_left_back",
        /// Right knee girth at the front of the leg.
        KneeRightFront = "knee_right_front",
        /// Right knee girth at the back of the leg.
        KneeRightBack = "knee_right_back",
        /// Left ankle girth at the front of the leg.
        AnkleLeftFront = "ankle_left_front",
        /// Left ankle girth at the back of the leg.
        AnkleLeftBack = "ankle_left_back",
        /// Right ankle girth at the front of the leg.
        AnkleRightFront = "ankle_right_front",
        /// Right ankle girth at the back of the leg.
        AnkleRightBack = "ankle_right_back",
        /// Left upper-arm point: the upper-arm girth on the outside of the arm.
        UpperArmLeft = "upper_arm_left",
        /// Right upper-arm point.
        UpperArmRight = "upper_arm_right",
        /// Left elbow point (olecranon, ISO 8559-1 3.1.13), on the outside of the bent arm.
        ElbowLeft = "elbow_left",
        /// Right elbow point.
        ElbowRight = "elbow_right",
        /// Left wrist point (ulnar styloid, ISO 8559-1 3.1.14).
        WristLeft = "wrist_left",
        /// Right wrist point.
        WristRight = "wrist_right",
    }
}

/// A body axis used by curve rules.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Axis {
    /// Lateral, towards the body's left.
    X,
    /// Up.
    Y,
    /// Forward.
    Z,
    /// Towards the body's right.
    NegX,
}

impl Axis {
    /// The unit vector.
    pub fn vector(self) -> DVec3 {
        match self {
            Axis::X => DVec3::X,
            Axis::Y => DVec3::Y,
            Axis::Z => DVec3::Z,
            Axis::NegX => DVec3::NEG_X,
        }
    }
}

/// How a section's plane is found from its landmarks.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum PlaneRule {
    /// Least-squares plane through the landmarks, its normal turned
    /// towards +Y; horizontal through their mean if they span no plane.
    BestFit,
    /// Horizontal through the landmarks' mean height, lowered by the
    /// derivation option `chest_below_armpit_mm` (used for the chest).
    HorizontalBelowArmpit,
    /// Horizontal through the landmarks' mean height.
    Horizontal,
    /// Through the first two landmarks and containing the axis.
    Containing(Axis),
    /// Through the (first) landmark with this normal.
    Normal(Axis),
    /// Through the landmarks' mean with this normal.
    NormalThroughMean(Axis),
    /// Vertical, through the landmarks' mean, at this angle (degrees,
    /// positive towards the body's left) from the sagittal plane: normal
    /// `(cos θ, 0, −sin θ)`.
    VerticalAtAngle(f64),
    /// Through the first landmark, normal to the line from the second to
    /// the third (a limb's girth, across its axis).
    Across,
    /// Through the middle of a leg, containing Z: landmarks are the thigh
    /// and ankle side points and the crotch; the plane passes 55 % of the
    /// way from the crotch to the thigh side point and through the middle
    /// of the ankle's horizontal section at the ankle side point (half an
    /// ankle width, `ankle_half_width_mm`, inside it where there is none).
    LegSagittal,
}

/// Which loop of a plane section is the curve.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum LoopChoice {
    /// The loop that encloses the landmarks' centroid (torso girths).
    Encloses,
    /// The loop nearest to the landmarks (limbs, armholes).
    Nearest,
}

/// How a curve is derived from landmarks.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum CurveRule {
    /// A closed plane section.
    Section {
        /// Landmarks the plane is fitted to.
        landmarks: &'static [PointId],
        /// How the plane is found.
        plane: PlaneRule,
        /// Which loop is kept.
        choice: LoopChoice,
        /// The loop runs anticlockwise seen from the tip of this axis.
        orientation: Axis,
    },
    /// An open path through landmarks, in order.
    Path {
        /// The landmarks, first to last.
        landmarks: &'static [PointId],
        /// Depth axis `d`: each piece lies in the plane spanned by the
        /// chord and `d`.
        depth: Axis,
    },
}

/// Registry entry of a curve.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CurveDef {
    /// ID.
    pub id: CurveId,
    /// Human-readable name.
    pub name: &'static str,
    /// Derivation rule.
    pub rule: CurveRule,
}

/// Registry entry of a point: the crossing of two curves.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PointDef {
    /// ID.
    pub id: PointId,
    /// Human-readable name.
    pub name: &'static str,
    /// First curve `f1` (its tangent is `t(f1)` in Eq. (1)).
    pub f1: CurveId,
    /// Second curve `f2`.
    pub f2: CurveId,
    /// Which crossing of the two curves is the point.
    pub pick: Pick,
}

/// Which of several crossings of two curves is the feature point.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Pick {
    /// The one nearest the point's landmark.
    Landmark,
    /// The one farthest from the first curve's centroid in this direction
    /// (e.g. `[-1, 0, 0]`: the inside of the left leg). These points need
    /// no landmark.
    Toward([f64; 3]),
}

use PointId as P;

const fn girth4(f: P, b: P, l: P, r: P) -> [P; 4] {
    [f, b, l, r]
}
const NECK: [P; 4] = girth4(P::NeckFront, P::NeckBack, P::NeckLeft, P::NeckRight);
const BUST: [P; 4] = girth4(P::BustFront, P::BustBack, P::BustLeft, P::BustRight);
const UNDERBUST: [P; 4] = girth4(P::UnderbustFront, P::UnderbustBack, P::UnderbustLeft, P::UnderbustRight);
const WAIST: [P; 4] = girth4(P::WaistFront, P::WaistBack, P::WaistLeft, P::WaistRight);
const HIP: [P; 4] = girth4(P::HipFront, P::HipBack, P::HipLeft, P::HipRight);

const fn section(landmarks: &'static [P], plane: PlaneRule, choice: LoopChoice, orientation: Axis) -> CurveRule {
    CurveRule::Section { landmarks, plane, choice, orientation }
}

/// The girths: the closed horizontal (or neck) sections around the torso
/// and each leg, top to bottom (the pattern draws their lines inside a
/// piece, `pattern::assemble`; authoring keeps free nodes off their points
/// near their planes, `template::from_garment`).
pub const GIRTH_CURVES: [CurveId; 12] = [
    CurveId::NeckBase,
    CurveId::Chest,
    CurveId::Bust,
    CurveId::Underbust,
    CurveId::Waist,
    CurveId::Hip,
    CurveId::ThighLeft,
    CurveId::ThighRight,
    CurveId::KneeLeft,
    CurveId::KneeRight,
    CurveId::AnkleLeft,
    CurveId::AnkleRight,
];

/// Every curve of vocabulary version [`VOCABULARY_VERSION`].
pub const CURVES: &[CurveDef] = &[
    CurveDef {
        id: CurveId::NeckBase,
        name: "neck base girth",
        rule: section(&NECK, PlaneRule::BestFit, LoopChoice::Encloses, Axis::Y),
    },
    CurveDef {
        id: CurveId::Chest,
        name: "chest girth",
        rule: section(
            &[P::UnderarmLeft, P::UnderarmRight],
            PlaneRule::HorizontalBelowArmpit,
            LoopChoice::Encloses,
            Axis::Y,
        ),
    },
    CurveDef {
        id: CurveId::Bust,
        name: "bust girth",
        rule: section(&BUST, PlaneRule::Horizontal, LoopChoice::Encloses, Axis::Y),
    },
    CurveDef {
        id: CurveId::Underbust,
        name: "underbust girth",
        rule: section(&UNDERBUST, PlaneRule::Horizontal, LoopChoice::Encloses, Axis::Y),
    },
    CurveDef {
        id: CurveId::Waist,
        name: "waist girth",
        rule: section(&WAIST, PlaneRule::Horizontal, LoopChoice::Encloses, Axis::Y),
    },
    CurveDef {
        id: CurveId::Hip,
        name: "hip girth",
        rule: section(&HIP, PlaneRule::Horizontal, LoopChoice::Encloses, Axis::Y),
    },
    CurveDef {
        id: CurveId::ThighLeft,
        name: "left thigh girth",
        rule: section(&[P::ThighLeft], PlaneRule::Horizontal, LoopChoice::Nearest, Axis::Y),
    },
    CurveDef {
        id: CurveId::ThighRight,
        name: "right thigh girth",
        rule: section(&[P::ThighRight], PlaneRule::Horizontal, LoopChoice::Nearest, Axis::Y),
    },
    CurveDef {
        id: CurveId::KneeLeft,
        name: "left knee girth",
        rule: section(&[P::KneeLeft], PlaneRule::Horizontal, LoopChoice::Nearest, Axis::Y),
    },
    CurveDef {
        id: CurveId::KneeRight,
        name: "right knee girth",
        rule: section(&[P::KneeRight], PlaneRule::Horizontal, LoopChoice::Nearest, Axis::Y),
    },
    CurveDef {
        id: CurveId::AnkleLeft,
        name: "left ankle girth",
        rule: section(&[P::AnkleLeft], PlaneRule::Horizontal, LoopChoice::Nearest, Axis::Y),
    },
    CurveDef {
        id: CurveId::AnkleRight,
        name: "right ankle girth",
        rule: section(&[P::AnkleRight], PlaneRule::Horizontal, LoopChoice::Nearest, Axis::Y),
    },
    CurveDef {
        id: CurveId::ArmscyeLeft,
        name: "left armscye girth",
        rule: section(
            &[P::ShoulderLeft, P::UnderarmLeft],
            PlaneRule::Containing(Axis::Z),
            LoopChoice::Nearest,
            Axis::X,
        ),
    },
    CurveDef {
        id: CurveId::ArmscyeRight,
        name: "right armscye girth",
        rule: section(
            &[P::ShoulderRight, P::UnderarmRight],
            PlaneRule::Containing(Axis::Z),
            LoopChoice::Nearest,
            Axis::NegX,
        ),
    },
    CurveDef {
        id: CurveId::CentreFront,
        name: "centre front line",
        rule: CurveRule::Path {
            landmarks: &[P::NeckFront, P::BustFront, P::UnderbustFront, P::WaistFront, P::HipFront, P::Crotch],
            depth: Axis::Z,
        },
    },
    CurveDef {
        id: CurveId::CentreBack,
        name: "centre back line",
        rule: CurveRule::Path {
            landmarks: &[P::NeckBack, P::BustBack, P::UnderbustBack, P::WaistBack, P::HipBack, P::Crotch],
            depth: Axis::Z,
        },
    },
    CurveDef {
        id: CurveId::SideLineLeft,
        name: "left side line",
        rule: CurveRule::Path {
            landmarks: &[
                P::UnderarmLeft,
                P::BustLeft,
                P::UnderbustLeft,
                P::WaistLeft,
                P::HipLeft,
                P::ThighLeft,
                P::KneeLeft,
                P::AnkleLeft,
            ],
            depth: Axis::X,
        },
    },
    CurveDef {
        id: CurveId::SideLineRight,
        name: "right side line",
        rule: CurveRule::Path {
            landmarks: &[
                P::UnderarmRight,
                P::BustRight,
                P::UnderbustRight,
                P::WaistRight,
                P::HipRight,
                P::ThighRight,
                P::KneeRight,
                P::AnkleRight,
            ],
            depth: Axis::X,
        },
    },
    CurveDef {
        id: CurveId::ShoulderLineLeft,
        name: "left shoulder line",
        rule: CurveRule::Path { landmarks: &[P::NeckLeft, P::ShoulderLeft], depth: Axis::Y },
    },
    CurveDef {
        id: CurveId::ShoulderLineRight,
        name: "right shoulder line",
        rule: CurveRule::Path { landmarks: &[P::NeckRight, P::ShoulderRight], depth: Axis::Y },
    },
    CurveDef {
        id: CurveId::CrotchLine,
        name: "crotch line",
        rule: section(&[P::Crotch], PlaneRule::Normal(Axis::Z), LoopChoice::Nearest, Axis::Z),
    },
    CurveDef {
        id: CurveId::LegLineLeft,
        name: "left leg line",
        rule: section(
            &[P::ThighLeft, P::KneeLeft, P::AnkleLeft],
            PlaneRule::NormalThroughMean(Axis::Z),
            LoopChoice::Nearest,
            Axis::Z,
        ),
    },
    CurveDef {
        id: CurveId::LegLineRight,
        name: "right leg line",
        rule: section(
            &[P::ThighRight, P::KneeRight, P::AnkleRight],
            PlaneRule::NormalThroughMean(Axis::Z),
            LoopChoice::Nearest,
            Axis::Z,
        ),
    },
    CurveDef {
        id: CurveId::ObliqueFrontLeft,
        name: "oblique line front-left / back-right",
        rule: section(&WAIST, PlaneRule::VerticalAtAngle(45.0), LoopChoice::Nearest, Axis::Y),
    },
    CurveDef {
        id: CurveId::ObliqueFrontRight,
        name: "oblique line front-right / back-left",
        rule: section(&WAIST, PlaneRule::VerticalAtAngle(-45.0), LoopChoice::Nearest, Axis::Y),
    },
    CurveDef {
        id: CurveId::LegSagittalLeft,
        name: "left leg sagittal line",
        rule: section(&[P::ThighLeft, P::AnkleLeft, P::Crotch], PlaneRule::LegSagittal, LoopChoice::Nearest, Axis::X),
    },
    CurveDef {
        id: CurveId::LegSagittalRight,
        name: "right leg sagittal line",
        rule: section(
            &[P::ThighRight, P::AnkleRight, P::Crotch],
            PlaneRule::LegSagittal,
            LoopChoice::Nearest,
            Axis::NegX,
        ),
    },
    CurveDef {
        id: CurveId::UpperArmLeft,
        name: "left upper-arm girth",
        rule: section(
            &[P::UpperArmLeft, P::ShoulderLeft, P::ElbowLeft],
            PlaneRule::Across,
            LoopChoice::Nearest,
            Axis::X,
        ),
    },
    CurveDef {
        id: CurveId::UpperArmRight,
        name: "right upper-arm girth",
        rule: section(
            &[P::UpperArmRight, P::ShoulderRight, P::ElbowRight],
            PlaneRule::Across,
            LoopChoice::Nearest,
            Axis::NegX,
        ),
    },
    CurveDef {
        id: CurveId::ElbowLeft,
        name: "left elbow girth",
        rule: section(&[P::ElbowLeft, P::ShoulderLeft, P::WristLeft], PlaneRule::Across, LoopChoice::Nearest, Axis::X),
    },
    CurveDef {
        id: CurveId::ElbowRight,
        name: "right elbow girth",
        rule: section(
            &[P::ElbowRight, P::ShoulderRight, P::WristRight],
            PlaneRule::Across,
            LoopChoice::Nearest,
            Axis::NegX,
        ),
    },
    CurveDef {
        id: CurveId::WristLeft,
        name: "left wrist girth",
        rule: section(&[P::WristLeft, P::ElbowLeft, P::WristLeft], PlaneRule::Across, LoopChoice::Nearest, Axis::X),
    },
    CurveDef {
        id: CurveId::WristRight,
        name: "right wrist girth",
        rule: section(
            &[P::WristRight, P::ElbowRight, P::WristRight],
            PlaneRule::Across,
            LoopChoice::Nearest,
            Axis::NegX,
        ),
    },
    CurveDef {
        id: CurveId::ArmLineLeft,
        name: "left arm line",
        rule: CurveRule::Path {
            landmarks: &[P::ShoulderLeft, P::UpperArmLeft, P::ElbowLeft, P::WristLeft],
            depth: Axis::Y,
        },
    },
    CurveDef {
        id: CurveId::ArmLineRight,
        name: "right arm line",
        rule: CurveRule::Path {
            landmarks: &[P::ShoulderRight, P::UpperArmRight, P::ElbowRight, P::WristRight],
            depth: Axis::Y,
        },
    },
];

/// The arm curves (vocabulary version 3): derived only where their
/// landmarks are given ([`optional_curve`]) — a landmarks file of version
/// 2, a scan landmarked by hand for a skirt, has none — so that no body
/// needs arms to be graded in a garment without sleeves.
pub const ARM_CURVES: [CurveId; 8] = [
    CurveId::UpperArmLeft,
    CurveId::UpperArmRight,
    CurveId::ElbowLeft,
    CurveId::ElbowRight,
    CurveId::WristLeft,
    CurveId::WristRight,
    CurveId::ArmLineLeft,
    CurveId::ArmLineRight,
];

/// Whether a body may lack `curve` (and the points on it): the arm curves.
pub fn optional_curve(curve: CurveId) -> bool {
    ARM_CURVES.contains(&curve)
}

/// Whether a body may lack `point`: a point on an optional curve.
pub fn optional_point(point: PointId) -> bool {
    let d = point_def(point);
    optional_curve(d.f1) || optional_curve(d.f2)
}

const fn pt(id: P, name: &'static str, f1: CurveId, f2: CurveId) -> PointDef {
    PointDef { id, name, f1, f2, pick: Pick::Landmark }
}

const fn toward(id: P, name: &'static str, f1: CurveId, f2: CurveId, dir: [f64; 3]) -> PointDef {
    PointDef { id, name, f1, f2, pick: Pick::Toward(dir) }
}

/// Every feature point of vocabulary version [`VOCABULARY_VERSION`].
pub const POINTS: &[PointDef] = &[
    pt(P::NeckFront, "front neck point", CurveId::NeckBase, CurveId::CentreFront),
    pt(P::NeckBack, "back neck point (cervicale)", CurveId::NeckBase, CurveId::CentreBack),
    pt(P::NeckLeft, "left side neck point", CurveId::NeckBase, CurveId::ShoulderLineLeft),
    pt(P::NeckRight, "right side neck point", CurveId::NeckBase, CurveId::ShoulderLineRight),
    pt(P::ShoulderLeft, "left shoulder point (acromion)", CurveId::ShoulderLineLeft, CurveId::ArmscyeLeft),
    pt(P::ShoulderRight, "right shoulder point (acromion)", CurveId::ShoulderLineRight, CurveId::ArmscyeRight),
    pt(P::UnderarmLeft, "left armpit point", CurveId::Chest, CurveId::SideLineLeft),
    pt(P::UnderarmRight, "right armpit point", CurveId::Chest, CurveId::SideLineRight),
    pt(P::ChestFront, "chest front point", CurveId::Chest, CurveId::CentreFront),
    pt(P::ChestBack, "chest back point", CurveId::Chest, CurveId::CentreBack),
    pt(P::BustFront, "bust front point", CurveId::Bust, CurveId::CentreFront),
    pt(P::BustBack, "bust back point", CurveId::Bust, CurveId::CentreBack),
    pt(P::BustLeft, "bust left side point", CurveId::Bust, CurveId::SideLineLeft),
    pt(P::BustRight, "bust right side point", CurveId::Bust, CurveId::SideLineRight),
    pt(P::UnderbustFront, "underbust front point", CurveId::Underbust, CurveId::CentreFront),
    pt(P::UnderbustBack, "underbust back point", CurveId::Underbust, CurveId::CentreBack),
    pt(P::UnderbustLeft, "underbust left side point", CurveId::Underbust, CurveId::SideLineLeft),
    pt(P::UnderbustRight, "underbust right side point", CurveId::Underbust, CurveId::SideLineRight),
    pt(P::WaistFront, "front waist point", CurveId::Waist, CurveId::CentreFront),
    pt(P::WaistBack, "back waist point", CurveId::Waist, CurveId::CentreBack),
    pt(P::WaistLeft, "left side waist point", CurveId::Waist, CurveId::SideLineLeft),
    pt(P::WaistRight, "right side waist point", CurveId::Waist, CurveId::SideLineRight),
    pt(P::HipFront, "front hip point", CurveId::Hip, CurveId::CentreFront),
    pt(P::HipBack, "back hip point", CurveId::Hip, CurveId::CentreBack),
    pt(P::HipLeft, "left side hip point", CurveId::Hip, CurveId::SideLineLeft),
    pt(P::HipRight, "right side hip point", CurveId::Hip, CurveId::SideLineRight),
    pt(P::Crotch, "crotch point", CurveId::CentreFront, CurveId::CrotchLine),
    pt(P::ThighLeft, "left thigh side point", CurveId::ThighLeft, CurveId::SideLineLeft),
    pt(P::ThighRight, "right thigh side point", CurveId::ThighRight, CurveId::SideLineRight),
    pt(P::KneeLeft, "left knee side point", CurveId::KneeLeft, CurveId::SideLineLeft),
    pt(P::KneeRight, "right knee side point", CurveId::KneeRight, CurveId::SideLineRight),
    pt(P::AnkleLeft, "left ankle side point", CurveId::AnkleLeft, CurveId::SideLineLeft),
    pt(P::AnkleRight, "right ankle side point", CurveId::AnkleRight, CurveId::SideLineRight),
    toward(P::ThighLeftInner, "left inner thigh point", CurveId::ThighLeft, CurveId::LegLineLeft, [-1.0, 0.0, 0.0]),
    toward(P::ThighRightInner, "right inner thigh point", CurveId::ThighRight, CurveId::LegLineRight, [1.0, 0.0, 0.0]),
    toward(P::KneeLeftInner, "left inner knee point", CurveId::KneeLeft, CurveId::LegLineLeft, [-1.0, 0.0, 0.0]),
    toward(P::KneeRightInner, "right inner knee point", CurveId::KneeRight, CurveId::LegLineRight, [1.0, 0.0, 0.0]),
    toward(P::AnkleLeftInner, "left inner ankle point", CurveId::AnkleLeft, CurveId::LegLineLeft, [-1.0, 0.0, 0.0]),
    toward(P::AnkleRightInner, "right inner ankle point", CurveId::AnkleRight, CurveId::LegLineRight, [1.0, 0.0, 0.0]),
    toward(
        P::NeckFrontLeft,
        "neck base front-left point",
        CurveId::NeckBase,
        CurveId::ObliqueFrontLeft,
        [1.0, 0.0, 1.0],
    ),
    toward(
        P::NeckBackLeft,
        "neck base back-left point",
        CurveId::NeckBase,
        CurveId::ObliqueFrontRight,
        [1.0, 0.0, -1.0],
    ),
    toward(
        P::NeckBackRight,
        "neck base back-right point",
        CurveId::NeckBase,
        CurveId::ObliqueFrontLeft,
        [-1.0, 0.0, -1.0],
    ),
    toward(
        P::NeckFrontRight,
        "neck base front-right point",
        CurveId::NeckBase,
        CurveId::ObliqueFrontRight,
        [-1.0, 0.0, 1.0],
    ),
    toward(P::ChestFrontLeft, "chest front-left point", CurveId::Chest, CurveId::ObliqueFrontLeft, [1.0, 0.0, 1.0]),
    toward(P::ChestBackLeft, "chest back-left point", CurveId::Chest, CurveId::ObliqueFrontRight, [1.0, 0.0, -1.0]),
    toward(P::ChestBackRight, "chest back-right point", CurveId::Chest, CurveId::ObliqueFrontLeft, [-1.0, 0.0, -1.0]),
    toward(P::ChestFrontRight, "chest front-right point", CurveId::Chest, CurveId::ObliqueFrontRight, [-1.0, 0.0, 1.0]),
    toward(P::BustFrontLeft, "bust front-left point", CurveId::Bust, CurveId::ObliqueFrontLeft, [1.0, 0.0, 1.0]),
    toward(P::BustBackLeft, "bust back-left point", CurveId::Bust, CurveId::ObliqueFrontRight, [1.0, 0.0, -1.0]),
    toward(P::BustBackRight, "bust back-right point", CurveId::Bust, CurveId::ObliqueFrontLeft, [-1.0, 0.0, -1.0]),
    toward(P::BustFrontRight, "bust front-right point", CurveId::Bust, CurveId::ObliqueFrontRight, [-1.0, 0.0, 1.0]),
    toward(
        P::UnderbustFrontLeft,
        "underbust front-left point",
        CurveId::Underbust,
        CurveId::ObliqueFrontLeft,
        [1.0, 0.0, 1.0],
    ),
    toward(
        P::UnderbustBackLeft,
        "underbust back-left point",
        CurveId::Underbust,
        CurveId::ObliqueFrontRight,
        [1.0, 0.0, -1.0],
    ),
    toward(
        P::UnderbustBackRight,
        "underbust back-right point",
        CurveId::Underbust,
        CurveId::ObliqueFrontLeft,
        [-1.0, 0.0, -1.0],
    ),
    toward(
        P::UnderbustFrontRight,
        "underbust front-right point",
        CurveId::Underbust,
        CurveId::ObliqueFrontRight,
        [-1.0, 0.0, 1.0],
    ),
    toward(P::WaistFrontLeft, "waist front-left point", CurveId::Waist, CurveId::ObliqueFrontLeft, [1.0, 0.0, 1.0]),
    toward(P::WaistBackLeft, "waist back-left point", CurveId::Waist, CurveId::ObliqueFrontRight, [1.0, 0.0, -1.0]),
    toward(P::WaistBackRight, "waist back-right point", CurveId::Waist, CurveId::ObliqueFrontLeft, [-1.0, 0.0, -1.0]),
    toward(P::WaistFrontRight, "waist front-right point", CurveId::Waist, CurveId::ObliqueFrontRight, [-1.0, 0.0, 1.0]),
    toward(P::HipFrontLeft, "hip front-left point", CurveId::Hip, CurveId::ObliqueFrontLeft, [1.0, 0.0, 1.0]),
    toward(P::HipBackLeft, "hip back-left point", CurveId::Hip, CurveId::ObliqueFrontRight, [1.0, 0.0, -1.0]),
    toward(P::HipBackRight, "hip back-right point", CurveId::Hip, CurveId::ObliqueFrontLeft, [-1.0, 0.0, -1.0]),
    toward(P::HipFrontRight, "hip front-right point", CurveId::Hip, CurveId::ObliqueFrontRight, [-1.0, 0.0, 1.0]),
    toward(P::ThighLeftFront, "left thigh front point", CurveId::ThighLeft, CurveId::LegSagittalLeft, [0.0, 0.0, 1.0]),
    toward(P::ThighLeftBack, "left thigh back point", CurveId::ThighLeft, CurveId::LegSagittalLeft, [0.0, 0.0, -1.0]),
    toward(
        P::ThighRightFront,
        "right thigh front point",
        CurveId::ThighRight,
        CurveId::LegSagittalRight,
        [0.0, 0.0, 1.0],
    ),
    toward(
        P::ThighRightBack,
        "right thigh back point",
        CurveId::ThighRight,
        CurveId::LegSagittalRight,
        [0.0, 0.0, -1.0],
    ),
    toward(P::KneeLeftFront, "left knee front point", CurveId::KneeLeft, CurveId::LegSagittalLeft, [0.0, 0.0, 1.0]),
    toward(P::KneeLeftBack, "left knee back point", CurveId::KneeLeft, CurveId::LegSagittalLeft, [0.0, 0.0, -1.0]),
    toward(P::KneeRightFront, "right knee front point", CurveId::KneeRight, CurveId::LegSagittalRight, [0.0, 0.0, 1.0]),
    toward(P::KneeRightBack, "right knee back point", CurveId::KneeRight, CurveId::LegSagittalRight, [0.0, 0.0, -1.0]),
    toward(P::AnkleLeftFront, "left ankle front point", CurveId::AnkleLeft, CurveId::LegSagittalLeft, [0.0, 0.0, 1.0]),
    toward(P::AnkleLeftBack, "left ankle back point", CurveId::AnkleLeft, CurveId::LegSagittalLeft, [0.0, 0.0, -1.0]),
    toward(
        P::AnkleRightFront,
        "right ankle front point",
        CurveId::AnkleRight,
        CurveId::LegSagittalRight,
        [0.0, 0.0, 1.0],
    ),
    toward(
        P::AnkleRightBack,
        "right ankle back point",
        CurveId::AnkleRight,
        CurveId::LegSagittalRight,
        [0.0, 0.0, -1.0],
    ),
    pt(P::UpperArmLeft, "left upper-arm point", CurveId::UpperArmLeft, CurveId::ArmLineLeft),
    pt(P::UpperArmRight, "right upper-arm point", CurveId::UpperArmRight, CurveId::ArmLineRight),
    pt(P::ElbowLeft, "left elbow point", CurveId::ElbowLeft, CurveId::ArmLineLeft),
    pt(P::ElbowRight, "right elbow point", CurveId::ElbowRight, CurveId::ArmLineRight),
    pt(P::WristLeft, "left wrist point", CurveId::WristLeft, CurveId::ArmLineLeft),
    pt(P::WristRight, "right wrist point", CurveId::WristRight, CurveId::ArmLineRight),
];

/// The registry entry of a curve.
pub fn curve_def(id: CurveId) -> &'static CurveDef {
    // CURVES is in CurveId order (checked by a test).
    &CURVES[id as usize]
}

/// The registry entry of a point.
pub fn point_def(id: PointId) -> &'static PointDef {
    &POINTS[id as usize]
}

/// The landmarks a scan must provide: every landmark named by the rule of
/// a curve every body has (not the [`ARM_CURVES`]).
pub fn required_landmarks() -> Vec<PointId> {
    let mut out: Vec<PointId> = CURVES
        .iter()
        .filter(|c| !optional_curve(c.id))
        .flat_map(|c| match c.rule {
            CurveRule::Section { landmarks, .. } | CurveRule::Path { landmarks, .. } => landmarks.iter().copied(),
        })
        .collect();
    out.sort();
    out.dedup();
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn registry_is_in_id_order_and_round_trips() {
        for (i, c) in CURVES.iter().enumerate() {
            assert_eq!(c.id as usize, i, "{}", c.id);
            assert_eq!(c.id.as_str().parse::<CurveId>().unwrap(), c.id);
        }
        assert_eq!(CURVES.len(), CurveId::ALL.len());
        for (i, p) in POINTS.iter().enumerate() {
            assert_eq!(p.id as usize, i, "{}", p.id);
            assert_eq!(p.id.as_str().parse::<PointId>().unwrap(), p.id);
            assert_ne!(p.f1, p.f2);
        }
        assert_eq!(POINTS.len(), PointId::ALL.len());
    }

    #[test]
    fn every_point_is_a_landmark_of_its_curves_or_a_crossing() {
        // Each point's two curves exist, and the landmarks needed cover
        // every point except the chest front/back crossings.
        let req = required_landmarks();
        for p in PointId::ALL {
            if !matches!(p, P::ChestFront | P::ChestBack) && point_def(*p).pick == Pick::Landmark {
                // the arms' points are landmarks of their (optional) curves
                let optional = optional_point(*p)
                    && CURVES.iter().any(|c| match c.rule {
                        CurveRule::Section { landmarks, .. } | CurveRule::Path { landmarks, .. } => {
                            optional_curve(c.id) && landmarks.contains(p)
                        }
                    });
                assert!(req.contains(p) || optional, "{p} is not a landmark");
                assert!(!(req.contains(p) && optional_point(*p)), "{p}: an optional point is not required");
            }
        }
    }

    #[test]
    fn unknown_ids_are_named() {
        let e = "waist_middle".parse::<PointId>().unwrap_err();
        assert_eq!(e.id, "waist_middle");
        assert!(e.to_string().contains("waist_middle"));
    }
}
