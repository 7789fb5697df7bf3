//! Small problems with known answers, and every error.

use phri_qp::{solve, Problem, QpError, Settings, Start, Workspace};

fn ws() -> Workspace {
    Workspace::new(3, 4, Settings::default()).expect("workspace")
}

#[test]
fn known_answer() {
    // min ½(x² + y²) + x  s.t.  x + 2y ≥ 1  →  (−0.6, 0.8), λ = 0.4
    let mut ws = ws();
    let h = [1.0, 0.0, 0.0, 1.0];
    let p = Problem {
        n: 2,
        h: &h,
        g: &[1.0, 0.0],
        c: &[-1.0, -2.0],
        d: &[-1.0],
        bounds: None,
    };
    let sol = solve(&mut ws, &p, Start::Cold).expect("solve");
    assert!(
        (sol.x[0] + 0.6).abs() < 1e-12 && (sol.x[1] - 0.8).abs() < 1e-12,
        "{:?}",
        sol.x
    );
    assert!((sol.lambda[0] - 0.4).abs() < 1e-12, "{:?}", sol.lambda);
    assert_eq!(sol.active, &[0]);
    assert!((sol.objective - (0.5 * (0.36 + 0.64) - 0.6)).abs() < 1e-12);
}

#[test]
fn bounds_in_the_layout() {
    // min ½|x − (2, −2)|²  s.t.  −1 ≤ x ≤ 1  →  (1, −1); λ_hi0 = 1, λ_lo1 = 1
    let mut ws = ws();
    let h = [1.0, 0.0, 0.0, 1.0];
    let (lo, hi) = ([-1.0, -1.0], [1.0, 1.0]);
    let p = Problem {
        n: 2,
        h: &h,
        g: &[-2.0, 2.0],
        c: &[],
        d: &[],
        bounds: Some((&lo, &hi)),
    };
    let sol = solve(&mut ws, &p, Start::Cold).expect("solve");
    assert_eq!(sol.lambda.len(), 4);
    assert!((sol.x[0] - 1.0).abs() < 1e-12 && (sol.x[1] + 1.0).abs() < 1e-12);
    // layout: hi0, hi1, lo0, lo1
    assert!((sol.lambda[0] - 1.0).abs() < 1e-12 && sol.lambda[1] == 0.0);
    assert!(sol.lambda[2] == 0.0 && (sol.lambda[3] - 1.0).abs() < 1e-12);
}

#[test]
fn unconstrained_and_inactive_rows() {
    let mut ws = ws();
    let h = [2.0, 0.0, 0.0, 4.0];
    let p = Problem {
        n: 2,
        h: &h,
        g: &[-2.0, -4.0],
        c: &[1.0, 1.0, 0.0, 0.0],
        d: &[5.0, 0.0],
        bounds: None,
    };
    let sol = solve(&mut ws, &p, Start::Cold).expect("solve");
    assert!(
        (sol.x[0] - 1.0).abs() < 1e-14 && (sol.x[1] - 1.0).abs() < 1e-14,
        "{:?}",
        sol.x
    );
    assert_eq!(sol.iterations, 0);
    assert!(sol.active.is_empty());
}

#[test]
fn errors() {
    let mut ws = ws();
    let h = [1.0, 0.0, 0.0, 1.0];
    let base = Problem {
        n: 2,
        h: &h,
        g: &[0.0, 0.0],
        c: &[1.0, 0.0],
        d: &[1.0],
        bounds: None,
    };
    let err = |ws: &mut Workspace, p: &Problem| solve(ws, p, Start::Cold).err();

    let not_pd = [1.0, 2.0, 2.0, 1.0];
    assert!(matches!(
        err(&mut ws, &Problem { h: &not_pd, ..base }),
        Some(QpError::NotPositiveDefinite { .. })
    ));
    let singular = [1.0, 1.0, 1.0, 1.0];
    assert!(matches!(
        err(
            &mut ws,
            &Problem {
                h: &singular,
                ..base
            }
        ),
        Some(QpError::NotPositiveDefinite { .. })
    ));
    assert!(matches!(
        err(&mut ws, &Problem { g: &[0.0], ..base }),
        Some(QpError::BadSize { what: "g", .. })
    ));
    assert!(matches!(
        err(&mut ws, &Problem { c: &[1.0], ..base }),
        Some(QpError::BadSize { what: "c", .. })
    ));
    assert!(matches!(
        err(&mut ws, &Problem { n: 4, ..base }),
        Some(QpError::BadSize { what: "n", .. })
    ));
    assert!(matches!(
        err(&mut ws, &Problem { n: 0, ..base }),
        Some(QpError::BadSize { .. })
    ));
    let many = [0.0; 10];
    assert!(matches!(
        err(
            &mut ws,
            &Problem {
                c: &[0.0; 20],
                d: &many,
                ..base
            }
        ),
        Some(QpError::BadSize { .. })
    ));
    assert!(matches!(
        err(
            &mut ws,
            &Problem {
                g: &[f64::NAN, 0.0],
                ..base
            }
        ),
        Some(QpError::NonFinite { what: "g" })
    ));
    assert!(matches!(
        err(
            &mut ws,
            &Problem {
                d: &[f64::INFINITY],
                ..base
            }
        ),
        Some(QpError::NonFinite { what: "d" })
    ));
    let (lo, hi) = ([f64::NAN, 0.0], [1.0, 1.0]);
    assert!(matches!(
        err(
            &mut ws,
            &Problem {
                bounds: Some((&lo, &hi)),
                ..base
            }
        ),
        Some(QpError::NonFinite { what: "bounds" })
    ));
    let (lo, hi) = ([0.0, 2.0], [1.0, 1.0]);
    assert!(matches!(
        err(
            &mut ws,
            &Problem {
                bounds: Some((&lo, &hi)),
                ..base
            }
        ),
        Some(QpError::Infeasible { row: 4 })
    ));
    // a zero row with a negative right-hand side
    assert!(matches!(
        err(
            &mut ws,
            &Problem {
                c: &[0.0, 0.0],
                d: &[-1.0],
                ..base
            }
        ),
        Some(QpError::Infeasible { row: 0 })
    ));
    // a zero row with a non-negative one binds nothing
    assert!(solve(
        &mut ws,
        &Problem {
            c: &[0.0, 0.0],
            d: &[0.0],
            ..base
        },
        Start::Cold
    )
    .is_ok());
    assert!(Workspace::new(0, 4, Settings::default()).is_err());
    assert!(Workspace::new(
        2,
        4,
        Settings {
            feasibility_tol: f64::NAN,
            ..Settings::default()
        }
    )
    .is_err());
}

#[test]
fn iteration_limit() {
    let mut ws = Workspace::new(
        3,
        4,
        Settings {
            max_iterations: 1,
            ..Settings::default()
        },
    )
    .expect("workspace");
    let h = [1.0, 0.0, 0.0, 1.0];
    // two rows bind at the optimum: two iterations needed
    let p = Problem {
        n: 2,
        h: &h,
        g: &[-2.0, -2.0],
        c: &[1.0, 0.0, 0.0, 1.0],
        d: &[1.0, 1.0],
        bounds: None,
    };
    assert_eq!(
        solve(&mut ws, &p, Start::Cold).err(),
        Some(QpError::IterationLimit { max_iterations: 1 })
    );
    let mut ws = Workspace::new(
        3,
        4,
        Settings {
            max_iterations: 2,
            ..Settings::default()
        },
    )
    .expect("workspace");
    let sol = solve(&mut ws, &p, Start::Cold).expect("two iterations suffice");
    assert!(
        (sol.x[0] - 1.0).abs() < 1e-14 && (sol.x[1] - 1.0).abs() < 1e-14,
        "{:?}",
        sol.x
    );
    assert_eq!(sol.iterations, 2);
}
