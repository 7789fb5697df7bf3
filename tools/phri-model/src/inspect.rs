//! `phri-model inspect`: every dynamics term at one state, as JSON.

use nalgebra::{DMatrix, Vector3};
use phri_model::{Data, Model};
use serde_json::{json, Map, Value};

use crate::{parse_vector, Flags};

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
pub(crate) fn load(path: &str) -> Result<Model, String> {
    Model::from_urdf_file(path).map_err(|e| e.to_string())
}

fn state(flags: &Flags, name: &str, n: usize, required: bool) -> Result<Vec<f64>, String> {
    match flags.get(name) {
        Some(text) => {
            let v = parse_vector(name, text)?;
            if v.len() != n {
                return Err(format!(
                    "{name}: expected {n} values (one per actuated joint), got {}",
                    v.len()
                ));
            }
            Ok(v)
        }
        None if required => Err(format!("{name} is required")),
        None => Ok(vec![0.0; n]),
    }
}

/// `LINK:x,y,z`
fn parse_point(model: &Model, text: &str) -> Result<(usize, Vector3<f64>), String> {
    let (link, xyz) = text
        .rsplit_once(':')
        .ok_or_else(|| format!("--point: expected LINK:x,y,z, got '{text}'"))?;
    let v = parse_vector("--point", xyz)?;
    if v.len() != 3 {
        return Err(format!("--point: expected 3 coordinates, got {}", v.len()));
    }
    let frame = model.frame_id(link).map_err(|e| format!("--point: {e}"))?;
    Ok((frame, Vector3::new(v[0], v[1], v[2])))
}

pub(crate) fn run(args: &[String]) -> Result<String, String> {
    let path = args.first().ok_or("inspect needs a URDF file")?;
    let flags = Flags::parse(&args[1..], &["--q", "--qd", "--qdd", "--point"])?;
    let model = load(path)?;
    let n = model.nv();
    let q = state(&flags, "--q", n, true)?;
    let qd = state(&flags, "--qd", n, false)?;
    let qdd = state(&flags, "--qdd", n, false)?;
    let point = flags
        .get("--point")
        .map(|p| parse_point(&model, p))
        .transpose()?;

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
