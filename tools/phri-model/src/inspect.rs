//! `phri-model inspect`: every dynamics term at one state, as JSON.

use std::path::{Path, PathBuf};

use nalgebra::{DMatrix, Vector3};
use phri_model::{Data, Model};
use serde_json::{json, Map, Value};

use crate::{parse_values, Values};

/// `phri-model inspect`'s arguments.
#[derive(clap::Args, Debug)]
pub(crate) struct InspectArgs {
    /// Robot description (URDF)
    #[arg(value_name = "ROBOT.urdf")]
    urdf: PathBuf,
    /// Joint positions [rad or m], one per actuated joint in the order of `joints` (mimic joints follow their leader)
    #[arg(long, value_name = "v1,v2,…", required = true, allow_hyphen_values = true, value_parser = parse_values)]
    q: Option<Values>,
    /// Joint velocities [rad/s or m/s] [default: zero]
    #[arg(long, value_name = "v1,v2,…", allow_hyphen_values = true, value_parser = parse_values)]
    qd: Option<Values>,
    /// Joint accelerations [rad/s² or m/s²] for tau (RNEA) [default: zero]
    #[arg(long, value_name = "v1,v2,…", allow_hyphen_values = true, value_parser = parse_values)]
    qdd: Option<Values>,
    /// Also print the Jacobian of point x,y,z \[m\] fixed in link LINK's frame
    #[arg(long, value_name = "LINK:x,y,z", allow_hyphen_values = true, value_parser = parse_point)]
    point: Option<(String, Vector3<f64>)>,
}

/// `m` as rows of numbers; an entry that is not finite (JSON has no NaN or
/// ∞: it would print as `null`) is refused naming the term `what`.
fn matrix_json<R: nalgebra::Dim, C: nalgebra::Dim, S: nalgebra::RawStorage<f64, R, C>>(
    what: &str,
    m: &nalgebra::Matrix<f64, R, C, S>,
) -> Result<Value, String> {
    finite(what, m.iter())?;
    Ok(Value::Array(
        (0..m.nrows())
            .map(|i| Value::Array((0..m.ncols()).map(|j| json!(m[(i, j)])).collect()))
            .collect(),
    ))
}

fn vector_json(what: &str, v: &nalgebra::DVector<f64>) -> Result<Value, String> {
    finite(what, v.iter())?;
    Ok(Value::Array(v.iter().map(|x| json!(x)).collect()))
}

fn finite<'a>(what: &str, mut values: impl Iterator<Item = &'a f64>) -> Result<(), String> {
    match values.find(|x| !x.is_finite()) {
        None => Ok(()),
        Some(x) => Err(format!(
            "{what} has a non-finite entry ({x}): the inputs or the model's numbers overflow"
        )),
    }
}

/// Load a URDF and map the library error to one line.
pub(crate) fn load(path: &Path) -> Result<Model, String> {
    Model::from_urdf_file(path).map_err(|e| e.to_string())
}

/// The values of flag `name`, one per actuated joint; zeros when not given.
fn state(name: &str, values: &Option<Values>, n: usize) -> Result<Vec<f64>, String> {
    match values {
        Some(Values(v)) if v.len() != n => Err(format!(
            "{name}: expected {n} values (one per actuated joint), got {}",
            v.len()
        )),
        Some(Values(v)) => Ok(v.clone()),
        None => Ok(vec![0.0; n]),
    }
}

/// `LINK:x,y,z` (the link is looked up once the model is loaded)
fn parse_point(text: &str) -> Result<(String, Vector3<f64>), String> {
    let (link, xyz) = text
        .rsplit_once(':')
        .ok_or_else(|| format!("expected LINK:x,y,z, got '{text}'"))?;
    let Values(v) = parse_values(xyz)?;
    if v.len() != 3 {
        return Err(format!("expected 3 coordinates, got {}", v.len()));
    }
    Ok((link.to_string(), Vector3::new(v[0], v[1], v[2])))
}

/// Each mimic joint with the actuated joint it follows:
/// `q = multiplier · q_leader + offset`.
fn mimic_json(model: &Model) -> Value {
    Value::Array(
        model
            .mimic_joints()
            .iter()
            .filter_map(|j| {
                let m = j.mimic?;
                Some(json!({
                    "joint": j.name,
                    "leader": model.joints[m.leader].name,
                    "multiplier": m.multiplier,
                    "offset": m.offset,
                }))
            })
            .collect(),
    )
}

pub(crate) fn run(args: &InspectArgs) -> Result<String, String> {
    let model = load(&args.urdf)?;
    let n = model.nv();
    let q = state("--q", &args.q, n)?;
    let qd = state("--qd", &args.qd, n)?;
    let qdd = state("--qdd", &args.qdd, n)?;
    let point = match &args.point {
        Some((link, x)) => Some((
            model.frame_id(link).map_err(|e| format!("--point: {e}"))?,
            *x,
        )),
        None => None,
    };

    let mut data = Data::new(&model);
    let e = |e: phri_model::ModelError| e.to_string();
    let m: DMatrix<f64> = phri_model::crba(&model, &mut data, &q).map_err(e)?.clone();
    let c = phri_model::coriolis_matrix(&model, &mut data, &q, &qd)
        .map_err(e)?
        .clone();
    let c_qd = phri_model::coriolis_times_qd(&model, &mut data, &q, &qd)
        .map_err(e)?
        .clone();
    phri_model::residual_terms(&model, &mut data, &q, &qd).map_err(e)?;
    let (ct_qd, g, p) = (data.ct_qd.clone(), data.g.clone(), data.p.clone());
    let tau = phri_model::rnea(&model, &mut data, &q, &qd, &qdd)
        .map_err(e)?
        .clone();
    phri_model::forward_kinematics(&model, &mut data, &q).map_err(e)?;
    let mut fk = Map::new();
    for (i, f) in model.frames.iter().enumerate() {
        let placement = phri_model::frame_placement(&model, &data, i).to_homogeneous();
        fk.insert(
            f.name.clone(),
            matrix_json(&format!("fk of {}", f.name), &placement)?,
        );
    }
    let mut out = Map::new();
    out.insert("robot".into(), json!(model.name));
    out.insert("joints".into(), json!(model.joint_names()));
    out.insert("mimic_joints".into(), mimic_json(&model));
    out.insert("M".into(), matrix_json("M", &m)?);
    out.insert("C".into(), matrix_json("C", &c)?);
    out.insert("C_qd".into(), vector_json("C_qd", &c_qd)?);
    out.insert("Ct_qd".into(), vector_json("Ct_qd", &ct_qd)?);
    out.insert("g".into(), vector_json("g", &g)?);
    out.insert("tau".into(), vector_json("tau", &tau)?);
    out.insert("p".into(), vector_json("p", &p)?);
    out.insert("fk".into(), Value::Object(fk));
    if let Some((frame, x)) = point {
        let mut jac = Data::jacobian_buffer(&model);
        phri_model::point_jacobian(&model, &data, frame, &x, &mut jac).map_err(e)?;
        out.insert("jacobian".into(), matrix_json("jacobian", &jac)?);
    }
    serde_json::to_string(&Value::Object(out)).map_err(|e| e.to_string())
}
