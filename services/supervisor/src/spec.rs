//! Which of `[services.NAME]` run, and in which order. The specification
//! itself ([`ServiceSpec`]) is phri-config's.

use std::collections::BTreeMap;

pub use phri_config::{ServiceSpec, SupervisorConfig};

/// The enabled services in start order: by `(order, name)`. Shutdown runs
/// in the same order (the robot first: it brakes the arm as it exits).
pub fn in_start_order(services: &BTreeMap<String, ServiceSpec>) -> Vec<(String, ServiceSpec)> {
    let mut list: Vec<(String, ServiceSpec)> = services
        .iter()
        .filter(|(_, s)| s.enabled)
        .map(|(n, s)| (n.clone(), s.clone()))
        .collect();
    list.sort_by(|(na, a), (nb, b)| (a.order, na).cmp(&(b.order, nb)));
    list
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn enabled_services_by_order_then_name() {
        let mut services = phri_config::Config::defaults().services;
        services.get_mut("camera").unwrap().enabled = false;
        let order: Vec<String> = in_start_order(&services)
            .into_iter()
            .map(|(n, _)| n)
            .collect();
        assert_eq!(
            order,
            [
                "sim",
                "dynamics",
                "dynamics_standby",
                "perception",
                "gesture",
                "repulsion0",
                "repulsion1",
                "repulsion2",
                "repulsion3",
                "control",
                "control_standby",
                "mic",
                "voice",
                "ros2"
            ]
        );
    }
}
