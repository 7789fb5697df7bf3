//! Services taken down for a while: deterministic fault injection.

/// Which service an [`Outage`] takes down.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Down {
    /// no new depth frames or repulsion results reach the controller
    Perception,
    /// the residual stops: the controller keeps seeing the last one, ageing
    Dynamics,
    /// no command from the first controller (`robot/command`): the robot
    /// reuses the last one, then brakes, unless the hot standby answers
    Control,
    /// no command from the hot standby (`robot/command/standby`)
    Standby,
    /// one camera of `[[camera]]` (by index) sends nothing, as a killed
    /// `camera` (index 0) or `camera-I` process: neither its frames' results
    /// nor its skeletons reach anyone; the other cameras go on
    Camera(usize),
}

impl Down {
    pub const ALL: [(Down, &'static str); 4] = [
        (Down::Perception, "perception"),
        (Down::Dynamics, "dynamics"),
        (Down::Control, "control"),
        (Down::Standby, "standby"),
    ];
}

/// A service down from `from_s` to `to_s` (robot time \[s\]).
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct Outage {
    pub service: Down,
    pub from_s: f64,
    pub to_s: f64,
}

/// An outage that is not `SERVICE:FROM:TO`.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
#[error(
    "outage: expected perception|dynamics|control|standby|camera|camera-I:FROM:TO (seconds, FROM ≤ TO, I a camera's index 1-3), got '{0}'"
)]
pub struct OutageError(pub String);

impl std::str::FromStr for Outage {
    type Err = OutageError;
    /// `perception:FROM:TO`, `dynamics:FROM:TO`, `control:FROM:TO`,
    /// `standby:FROM:TO`, `camera:FROM:TO` (the first camera) or
    /// `camera-I:FROM:TO` (seconds)
    fn from_str(s: &str) -> Result<Outage, OutageError> {
        let bad = || OutageError(s.to_string());
        let mut it = s.split(':');
        let name = it.next().ok_or_else(bad)?;
        let camera = match name {
            "camera" => Some(0),
            _ => name
                .strip_prefix("camera-")
                .and_then(|i| i.parse::<usize>().ok())
                .filter(|i| (1..phri_ipc::MAX_CAMERAS).contains(i)),
        };
        let service = match camera {
            Some(i) => Down::Camera(i),
            None => Down::ALL
                .iter()
                .find(|(_, n)| *n == name)
                .map(|(d, _)| *d)
                .ok_or_else(bad)?,
        };
        let mut num = || {
            it.next()
                .and_then(|x| x.trim().parse::<f64>().ok())
                .ok_or_else(bad)
        };
        let (from_s, to_s) = (num()?, num()?);
        if it.next().is_some() || !(from_s.is_finite() && to_s.is_finite() && to_s >= from_s) {
            return Err(bad());
        }
        Ok(Outage {
            service,
            from_s,
            to_s,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_camera_s_outage_names_its_process() {
        let o: Outage = "camera-1:11:11.75".parse().unwrap();
        assert_eq!(
            o,
            Outage {
                service: Down::Camera(1),
                from_s: 11.0,
                to_s: 11.75
            }
        );
        let o: Outage = "camera:2:3".parse().unwrap();
        assert_eq!(o.service, Down::Camera(0));
        for bad in [
            "camera-0:1:2",
            "camera-4:1:2",
            "camera-x:1:2",
            "camera-1:2:1",
            "cam:1:2",
        ] {
            assert!(bad.parse::<Outage>().is_err(), "{bad}");
        }
    }
}
