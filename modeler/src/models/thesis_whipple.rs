//! The Whipple bicycle of the thesis (Martin Recuero 2009, section 3 and the
//! listing `Bicicleta.m`): four rigid bodies (2 rear wheel, 3 rear frame,
//! 4 handlebar + fork, 5 front wheel), knife-edge wheels rolling without slip
//! on flat ground, nine coordinates `p = [xc yc phi theta psi beta gamma eps xi]`.
//! Axes: X forward, Y left, Z up.

use crate::effects::BicycleParts;
use crate::expr::{exact, inertia_wheel, inertia_xz, num, rate, time, vec3, Expr};
use crate::model::{
    Axis, BodyId, CoordinateRole, Holonomic, Model, ModelBuilder, ModelError, Nonholonomic, ParameterRole, Role,
    SourceFile, Uncertainty, GROUND,
};
use std::f64::consts::PI;

const SOURCE: SourceFile = SourceFile::new("modeler/src/models/thesis_whipple.rs", include_str!("thesis_whipple.rs"));

/// How forward speed enters a bicycle model.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Speed {
    /// Imposed by the driving constraint `psi - V t / Rt = 0` (thesis eq. 26):
    /// independent coordinates roll and steer, parameter `V`.
    Driven,
    /// A degree of freedom: no driving constraint, the rear wheel rotation
    /// `psi` is an independent coordinate (roll, rear wheel rotation, steer),
    /// and the forward speed `Rt psi'` can change.
    Free,
}

/// Declare the thesis model under `name`, from the model file `source`
/// (variants start from here and add to the returned builder).
pub fn declare(name: &str, source: impl Into<SourceFile>, speed: Speed) -> (ModelBuilder, BicycleParts) {
    let source = source.into();
    let doc = match speed {
        Speed::Driven => {
            "Whipple bicycle of Martin Recuero (2009), section 3: 9 coordinates, driving constraint psi = V t / Rt"
        }
        Speed::Free => "Whipple bicycle of Martin Recuero (2009), section 3, with free forward speed (no driving constraint; rear wheel rotation psi independent)",
    };
    let mut m = Model::builder(name).doc(doc).source(SOURCE).source(source);
    m.set_base("thesis_whipple");
    let psi_role = match speed {
        Speed::Driven => Role::Dependent,
        Speed::Free => Role::Independent,
    };

    // 3.2 Coordinates: rear contact (xc, yc), yaw phi, roll theta, rear wheel
    // rotation psi, frame pitch beta, steer gamma, front wheel rotation eps,
    // and xi, the angle locating the front contact on the rim.
    let xc = m.coordinate("xc", Role::Ignorable, 0.0, "rear contact point, global X (m)");
    let yc = m.coordinate("yc", Role::Ignorable, 0.0, "rear contact point, global Y (m)");
    let phi = m.coordinate("phi", Role::Ignorable, 0.0, "yaw (rad)");
    let theta = m.coordinate("theta", Role::Independent, 0.0, "roll (rad), positive leaning right");
    let psi = m.coordinate(
        "psi",
        psi_role,
        0.0,
        "rear wheel rotation (rad), increasing when rolling forward",
    );
    let beta = m.coordinate(
        "beta",
        Role::Dependent,
        -PI / 10.0,
        "frame pitch (rad); minus the steer-axis tilt when upright",
    );
    let gamma = m.coordinate(
        "gamma",
        Role::Independent,
        0.0,
        "steer angle about the steer axis (rad), positive turning left",
    );
    let eps = m.coordinate("eps", Role::Ignorable, 0.0, "front wheel rotation (rad)");
    let xi = m.coordinate(
        "xi",
        Role::Dependent,
        PI / 2.0,
        "angle of the front contact point on the rim (rad)",
    );

    // What each coordinate means to the jobs (simulation output, residuals,
    // identification): declared here, never inferred from the names.
    for (c, r) in [
        ("xc", CoordinateRole::RearContactX),
        ("yc", CoordinateRole::RearContactY),
        ("phi", CoordinateRole::Yaw),
        ("theta", CoordinateRole::Roll),
        ("psi", CoordinateRole::RearWheelRotation),
        ("beta", CoordinateRole::Pitch),
        ("gamma", CoordinateRole::Steer),
        ("eps", CoordinateRole::FrontWheelRotation),
        ("xi", CoordinateRole::FrontContactRimAngle),
    ] {
        m.coordinate_role(c, r);
    }

    // Parameters (section 4.4, Parametros.m).
    let v = (speed == Speed::Driven).then(|| m.parameter("V", "forward speed imposed by the driving constraint (m/s)"));
    let rt = m.parameter("Rt", "rear wheel radius (m)");
    let rd = m.parameter("Rd", "front wheel radius (m)");
    let x3 = m.parameter("x3", "rear-frame mass centre from the rear wheel centre, frame x (m)");
    let z3 = m.parameter("z3", "rear-frame mass centre from the rear wheel centre, frame z (m)");
    let x4 = m.parameter("x4", "steer-axis point G4 from the rear wheel centre, frame x (m)");
    let z4 = m.parameter("z4", "steer-axis point G4 from the rear wheel centre, frame z (m)");
    let x5 = m.parameter("x5", "front wheel centre from G4, fork x (m)");
    let z5 = m.parameter("z5", "front wheel centre from G4, fork z (m)");
    let m2 = m.parameter("m2", "rear wheel mass (kg)");
    let m3 = m.parameter("m3", "rear frame mass (kg)");
    let m4 = m.parameter("m4", "handlebar + fork mass (kg)");
    let m5 = m.parameter("m5", "front wheel mass (kg)");
    let i2x = m.parameter("I2x", "rear wheel moment about a diameter (kg m^2)");
    let i2y = m.parameter("I2y", "rear wheel moment about its axle (kg m^2)");
    let i3x = m.parameter("I3x", "rear frame inertia xx, frame axes (kg m^2)");
    let i3y = m.parameter("I3y", "rear frame inertia yy (kg m^2)");
    let i3z = m.parameter("I3z", "rear frame inertia zz (kg m^2)");
    let i3zx = m.parameter("I3zx", "rear frame inertia xz (kg m^2)");
    let i4x = m.parameter("I4x", "handlebar + fork inertia xx, fork axes (kg m^2)");
    let i4y = m.parameter("I4y", "handlebar + fork inertia yy (kg m^2)");
    let i4z = m.parameter("I4z", "handlebar + fork inertia zz (kg m^2)");
    let i4xz = m.parameter("I4xz", "handlebar + fork inertia xz (kg m^2)");
    let i5x = m.parameter("I5x", "front wheel moment about a diameter (kg m^2)");
    let i5y = m.parameter("I5y", "front wheel moment about its axle (kg m^2)");
    m.parameter_role("Rt", ParameterRole::RearWheelRadius);
    m.parameter_role("Rd", ParameterRole::FrontWheelRadius);
    // How well a measured bicycle knows each parameter, when its file gives
    // no `+/-`: identification may correct a parameter within this
    // standard deviation. G4 and the front wheel centre fix trail and steer
    // tilt (a 5 mm error in them is about 1 deg of tilt).
    for (p, u) in [
        ("Rt", Uncertainty::WHEEL_RADIUS),
        ("Rd", Uncertainty::WHEEL_RADIUS),
        ("x3", Uncertainty::MASS_CENTRE),
        ("z3", Uncertainty::MASS_CENTRE),
        ("x4", Uncertainty::GEOMETRY),
        ("z4", Uncertainty::GEOMETRY),
        ("x5", Uncertainty::GEOMETRY),
        ("z5", Uncertainty::GEOMETRY),
        ("m2", Uncertainty::MASS),
        ("m3", Uncertainty::MASS),
        ("m4", Uncertainty::MASS),
        ("m5", Uncertainty::MASS),
        ("I2x", Uncertainty::INERTIA),
        ("I2y", Uncertainty::INERTIA),
        ("I3x", Uncertainty::INERTIA),
        ("I3y", Uncertainty::INERTIA),
        ("I3z", Uncertainty::INERTIA),
        ("I3zx", Uncertainty::INERTIA),
        ("I4x", Uncertainty::INERTIA),
        ("I4y", Uncertainty::INERTIA),
        ("I4z", Uncertainty::INERTIA),
        ("I4xz", Uncertainty::INERTIA),
        ("I5x", Uncertainty::INERTIA),
        ("I5y", Uncertainty::INERTIA),
    ] {
        m.uncertainty(p, u);
    }
    m.parameter("g", "gravitational acceleration (m/s^2)");
    m.gravity("g", Axis::Z);

    // The physical upright configuration in closed form: the frame pitch
    // that puts both wheels on the ground with the front wheel ahead,
    // Rt - sin(beta) P + cos(beta) Q = Rd with P = x4 + x5, Q = z4 + z5,
    // R = hypot(P, Q): beta = acos((Rd - Rt) / R) - atan2(P, Q), written
    // with acos(x) = pi/2 - atan(x / sqrt(1 - x^2)) and the half-angle form
    // atan2(P, Q) = 2 atan(P / (R + Q)); and the rim angle of the lowest
    // point of the front rim, xi = pi/2 - beta - eps.
    {
        let beta_up = upright_pitch(
            x4.clone() + x5.clone(),
            z4.clone() + z5.clone(),
            rt.clone(),
            rd.clone(),
        );
        m.upright_value("beta", beta_up.clone());
        m.upright_value("xi", exact(PI / 2.0) - beta_up - crate::expr::coord("eps"));
    }

    // 3.3 Rotations (eq. 4): Ai1 = A_phi, Ai2 = A_phi A_theta, A2 = Ai2 A_psi,
    // A3 = Ai2 A_beta, A4 = A3 A_gam, A5 = A4 A_eps.
    let yaw = m.frame("Ai1", GROUND, vec![(Axis::Z, phi)]);
    let roll = m.frame("Ai2", yaw, vec![(Axis::X, theta)]);
    let rear_wheel_frame = m.frame("A2", roll, vec![(Axis::Y, psi.clone())]);
    let frame = m.frame("A3", roll, vec![(Axis::Y, beta)]);
    let fork_frame = m.frame("A4", frame, vec![(Axis::Z, gamma)]);
    let front_wheel_frame = m.frame("A5", fork_frame, vec![(Axis::Y, eps)]);

    // 3.5 Mass centres (eq. 13-19).
    let g2 = m.point(
        "G2",
        None,
        vec![(GROUND, vec3(xc, yc, num(0))), (roll, vec3(num(0), num(0), rt.clone()))],
    );
    let g3 = m.point("G3", Some(g2), vec![(frame, vec3(x3, num(0), z3))]);
    let g4 = m.point("G4", Some(g2), vec![(frame, vec3(x4, num(0), z4))]);
    let g5 = m.point("G5", Some(g4), vec![(fork_frame, vec3(x5, num(0), z5))]);
    // Contact points: rear, straight below the rear wheel centre in the roll
    // frame; front (eq. 21), on the rim at angle xi.
    let rear_contact = m.point(
        "rear_contact",
        Some(g2),
        vec![(roll, vec3(num(0), num(0), -rt.clone()))],
    );
    let front_contact = m.point(
        "front_contact",
        Some(g5),
        vec![(
            front_wheel_frame,
            vec3(rd.clone() * xi.clone().cos(), num(0), -(rd * xi.sin())),
        )],
    );
    m.point_of_interest(rear_contact);
    m.point_of_interest(front_contact);

    // Bodies: mass, inertia tensor in body axes, mass centre.
    let rear_wheel: BodyId = m.body("rear_wheel", rear_wheel_frame, m2, inertia_wheel(i2x, i2y), g2);
    let rear_frame = m.body("rear_frame", frame, m3, inertia_xz(i3x, i3y, i3z, i3zx), g3);
    let fork = m.body("fork", fork_frame, m4, inertia_xz(i4x, i4y, i4z, i4xz), g4);
    let front_wheel = m.body("front_wheel", front_wheel_frame, m5, inertia_wheel(i5x, i5y), g5);

    // 3.6 Constraints. Front contact on the ground and lowest point of the rim
    // (eq. 21-22); driving constraint psi - V t / Rt = 0 (eq. 26, as coded).
    m.holonomic(Holonomic::PointComponent {
        name: "front_contact_height".into(),
        point: front_contact,
        axis: Axis::Z,
    });
    m.holonomic(Holonomic::PointComponentStationary {
        name: "front_contact_lowest".into(),
        point: front_contact,
        axis: Axis::Z,
        coordinate: "xi".into(),
    });
    match v {
        Some(v) => {
            m.holonomic(Holonomic::Residual {
                name: "driving".into(),
                expr: psi - v.clone() * time() / rt.clone(),
            });
            m.forward_speed(v);
        }
        None => {
            m.set_free_speed(true);
            m.forward_speed(rt.clone() * rate("psi"));
        }
    }
    // Rolling without slip (eq. 23-25).
    for (name, body, point, axis) in [
        ("rear_rolling_x", rear_wheel, rear_contact, Axis::X),
        ("rear_rolling_y", rear_wheel, rear_contact, Axis::Y),
        ("front_rolling_x", front_wheel, front_contact, Axis::X),
        ("front_rolling_y", front_wheel, front_contact, Axis::Y),
    ] {
        m.nonholonomic(Nonholonomic::ContactVelocity {
            name: name.into(),
            body,
            point,
            axis,
        });
    }
    (
        m,
        BicycleParts {
            rear_wheel,
            rear_frame,
            fork,
            front_wheel,
            rear_frame_axes: frame,
            fork_axes: fork_frame,
            rear_wheel_axes: rear_wheel_frame,
            front_wheel_axes: front_wheel_frame,
            rear_hub: g2,
            front_hub: g5,
            steer_point: g4,
            rear_frame_mass_centre: g3,
            rear_contact,
            front_contact,
            rear_contact_lateral: "yc".into(),
            yaw: "phi".into(),
            roll: "theta".into(),
            steer: "gamma".into(),
            rear_wheel_rotation: "psi".into(),
            front_wheel_rotation: "eps".into(),
            rear_wheel_radius: rt,
            front_wheel_radius: crate::expr::param("Rd"),
            gravity: crate::expr::param("g"),
        },
    )
}

/// The frame pitch that puts both wheels on the ground with the front
/// wheel ahead, from the front wheel centre `(p, q)` relative to the rear
/// one in frame axes and the wheel radii (see the upright configuration in
/// [`declare`]).
pub fn upright_pitch(p: Expr, q: Expr, rt: Expr, rd: Expr) -> Expr {
    let d = rd - rt;
    let r2 = p.clone().powi(2) + q.clone().powi(2);
    let r = r2.clone().sqrt();
    exact(PI / 2.0) - (d.clone() / (r2 - d.powi(2)).sqrt()).atan() - crate::expr::num(2) * (p / (r + q)).atan()
}

/// The thesis model.
pub fn model() -> Result<Model, ModelError> {
    declare("thesis_whipple", SOURCE, Speed::Driven).0.build()
}
