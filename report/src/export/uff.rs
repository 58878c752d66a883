//! Universal file format (UFF) writer: dataset 58, "function at nodal DOF", ASCII, for FRFs
//! (method.md §3.6), so that the FRFs of a recording open in the modal tools test engineers already use
//! (pyuff, sdypy-EMA, commercial suites). A pure writer: it returns bytes; writing the file is
//! the caller's step.
//!
//! # What is written
//!
//! One dataset 58 per FRF ([`Dataset58`]), in the layout of the dataset's definition (I-DEAS
//! universal file datasets, as documented with pyuff):
//!
//! * records 1-5: ID lines (80 columns; an empty line is written as `NONE`, as the format
//!   requires);
//! * record 6: function type 4 (frequency response function), function id, version 0, load case
//!   0 (single-point excitation), response entity `NONE`, response node and direction, reference
//!   entity `NONE`, reference node and direction;
//! * record 7: ordinate type 6 (complex, double precision), number of values, even abscissa
//!   spacing (1), abscissa minimum and increment in Hz (`E13.5`: six significant digits, the
//!   format's own; 0.1 Hz and 0.01 Hz bins are exact), z-axis value 0;
//! * records 8-11: data characteristics of the abscissa (18, frequency, `Frequency`, `Hz`), the
//!   ordinate numerator and denominator ([`Quantity`], with the units exponents of the format's
//!   table: length 1 for displacement, velocity and acceleration, force 1 for force) and the
//!   z axis (0, unused);
//! * record 12: the values as real and imaginary parts, `4E20.12` (two complex values a line).
//!
//! For the workspace's FRFs (acceleration over base acceleration, dimensionless) numerator and
//! denominator are both [`Quantity::Acceleration`] in `m/s^2`; readers that pick the FRF form
//! from the ordinate type (sdypy-EMA) then treat them as accelerance, which matches their
//! residual terms (see `vibcam_identify::modal`).

use num_complex::Complex64;

/// Function type of record 6 for a frequency response function.
pub const FUNCTION_TYPE_FRF: u32 = 4;

/// The physical quantity of an axis (records 8-11): its specific data type code and units
/// exponents (the format's table, translational directions).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[non_exhaustive]
pub enum Quantity {
    /// Code 0: unknown or unused.
    Unknown,
    /// Code 8: displacement (length exponent 1).
    Displacement,
    /// Code 11: velocity (length exponent 1).
    Velocity,
    /// Code 12: acceleration (length exponent 1).
    Acceleration,
    /// Code 13: excitation force (force exponent 1).
    ExcitationForce,
    /// Code 18: frequency (the abscissa).
    Frequency,
}

impl Quantity {
    /// Specific data type code.
    pub fn code(self) -> i32 {
        match self {
            Quantity::Unknown => 0,
            Quantity::Displacement => 8,
            Quantity::Velocity => 11,
            Quantity::Acceleration => 12,
            Quantity::ExcitationForce => 13,
            Quantity::Frequency => 18,
        }
    }

    /// Length, force and temperature units exponents.
    pub fn exponents(self) -> (i32, i32, i32) {
        match self {
            Quantity::Displacement | Quantity::Velocity | Quantity::Acceleration => (1, 0, 0),
            Quantity::ExcitationForce => (0, 1, 0),
            Quantity::Unknown | Quantity::Frequency => (0, 0, 0),
        }
    }
}

/// One axis's data characteristics (records 8-11).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct AxisCharacteristics {
    /// The quantity.
    pub quantity: Quantity,
    /// Axis label, at most 20 characters (`NONE` when empty).
    pub label: String,
    /// Units label, at most 20 characters (`NONE` when empty).
    pub units: String,
}

impl AxisCharacteristics {
    /// Acceleration in m/s^2.
    pub fn acceleration() -> Self {
        AxisCharacteristics {
            quantity: Quantity::Acceleration,
            label: "Acceleration".into(),
            units: "m/s^2".into(),
        }
    }

    fn frequency() -> Self {
        AxisCharacteristics {
            quantity: Quantity::Frequency,
            label: "Frequency".into(),
            units: "Hz".into(),
        }
    }

    fn unused() -> Self {
        AxisCharacteristics {
            quantity: Quantity::Unknown,
            label: String::new(),
            units: String::new(),
        }
    }
}

/// A node and direction of record 6: direction 0 scalar, 1/2/3 +X/+Y/+Z translation, negative
/// for the minus directions, 4-6 rotations.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Dof {
    /// Node number (at most 10 digits).
    pub node: u32,
    /// Direction code, -6..=6.
    pub direction: i32,
}

/// One FRF as a dataset 58: evenly spaced complex values from `f0_hz` in steps of `df_hz`.
#[derive(Debug, Clone, PartialEq)]
pub struct Dataset58<'a> {
    /// ID lines 1-5 (records 1-5), at most 80 characters each; line 1 is the function's
    /// description, line 3 by convention its date and time (`DD-MMM-YY HH:MM:SS`).
    pub id_lines: [String; 5],
    /// Function identification number (record 6, field 2).
    pub function_id: u32,
    /// Response node and direction (the target; the output accelerometer).
    pub response: Dof,
    /// Reference node and direction (the input channel).
    pub reference: Dof,
    /// Frequency of the first value, Hz.
    pub f0_hz: f64,
    /// Bin spacing, Hz, > 0.
    pub df_hz: f64,
    /// Ordinate numerator (the response's quantity).
    pub numerator: AxisCharacteristics,
    /// Ordinate denominator (the reference's quantity).
    pub denominator: AxisCharacteristics,
    /// The FRF values, one per bin.
    pub values: &'a [Complex64],
}

impl<'a> Dataset58<'a> {
    /// An acceleration-over-acceleration FRF (dimensionless; m/s^2 over m/s^2) from
    /// `reference` to `response`, with `description` as ID line 1.
    pub fn acceleration_frf(
        description: &str,
        function_id: u32,
        response: Dof,
        reference: Dof,
        f0_hz: f64,
        df_hz: f64,
        values: &'a [Complex64],
    ) -> Self {
        Dataset58 {
            id_lines: [
                description.to_string(),
                String::new(),
                String::new(),
                String::new(),
                String::new(),
            ],
            function_id,
            response,
            reference,
            f0_hz,
            df_hz,
            numerator: AxisCharacteristics::acceleration(),
            denominator: AxisCharacteristics::acceleration(),
            values,
        }
    }
}

/// What can make a dataset unwritable. Each names the function id.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum UffError {
    /// No values.
    #[error("UFF dataset 58, function {function_id}: no values")]
    Empty {
        /// The dataset's function id.
        function_id: u32,
    },
    /// A value is NaN or infinite.
    #[error("UFF dataset 58, function {function_id}: value {index} is not finite")]
    NotFinite {
        /// The dataset's function id.
        function_id: u32,
        /// Index of the value.
        index: usize,
    },
    /// The abscissa start or step is unusable.
    #[error("UFF dataset 58, function {function_id}: abscissa start {f0_hz} Hz, step {df_hz} Hz (need a finite start >= 0 and step > 0)")]
    Abscissa {
        /// The dataset's function id.
        function_id: u32,
        /// Start, Hz.
        f0_hz: f64,
        /// Step, Hz.
        df_hz: f64,
    },
    /// A text field is too long or holds a line break.
    #[error("UFF dataset 58, function {function_id}: {field} {text:?} is longer than {max} characters or not one line")]
    Text {
        /// The dataset's function id.
        function_id: u32,
        /// Which field.
        field: &'static str,
        /// The text.
        text: String,
        /// Its maximum length.
        max: usize,
    },
    /// A direction code outside -6..=6.
    #[error(
        "UFF dataset 58, function {function_id}: direction {direction} is not a DOF code (-6..=6)"
    )]
    Direction {
        /// The dataset's function id.
        function_id: u32,
        /// The code given.
        direction: i32,
    },
}

/// The accelerance FRFs of a rig seen by its accelerometer and by camera targets, each over
/// the base acceleration (node `base_node`, direction +Z): the accelerometer's `(name, node,
/// first line's frequency, H)` as function 1, then target `t`'s `(first line's frequency, H)`
/// as node `t + 1`, function `t + 2`, named `vision target t / base acceleration` (a target
/// without an FRF left out); lines `df_hz` apart.
pub fn vision_frfs<'a>(
    base_node: u32,
    accel: (&str, u32, f64, &'a [Complex64]),
    targets: &[Option<(f64, &'a [Complex64])>],
    df_hz: f64,
) -> Vec<Dataset58<'a>> {
    let z = |node: u32| Dof { node, direction: 3 };
    let (name, node, f0, h) = accel;
    let mut sets = vec![Dataset58::acceleration_frf(
        name,
        1,
        z(node),
        z(base_node),
        f0,
        df_hz,
        h,
    )];
    for (t, frf) in targets.iter().enumerate() {
        let Some((f0, h)) = frf else { continue };
        let name = format!("vision target {} / base acceleration", t + 1);
        let (node, function) = (t as u32 + 1, t as u32 + 2);
        sets.push(Dataset58::acceleration_frf(
            &name,
            function,
            z(node),
            z(base_node),
            *f0,
            df_hz,
            h,
        ));
    }
    sets
}

/// Several datasets 58, one after the other, as the bytes of a `.uff` file.
pub fn write_file(datasets: &[Dataset58<'_>]) -> Result<Vec<u8>, UffError> {
    let mut out = Vec::new();
    for d in datasets {
        out.extend(write_dataset58(d)?);
    }
    Ok(out)
}

/// One dataset 58 (see the module documentation for the records), from its `-1` delimiter line
/// to the closing one.
pub fn write_dataset58(d: &Dataset58<'_>) -> Result<Vec<u8>, UffError> {
    validate(d)?;
    let mut o = String::with_capacity(1200 + 42 * d.values.len());
    o.push_str("    -1\n    58\n");
    push_header_records(&mut o, d)?;
    push_characteristic_records(&mut o, d)?;
    push_data_records(&mut o, d);
    o.push_str("    -1\n");
    Ok(o.into_bytes())
}

/// One mode shape as a dataset 55, "data at nodes" (complex eigenvalue, first order):
/// record 6 model type 1 (structural), analysis type 3 (complex eigenvalue), data
/// characteristic 2 (three translations per node), specific data type 8 (displacement), data
/// type 5 (complex), 3 values per node; record 7 load case and mode number; record 8 the
/// eigenvalue `-zeta w + i w sqrt(1 - zeta^2)` (rad/s) and modal A and B (0); then per node its
/// number and the complex x, y, z components (`6E13.5`). Read by pyuff (`read_sets`: `eig`,
/// `node_nums`, `r1`, `r2`, `r3`).
#[derive(Debug, Clone, PartialEq)]
pub struct Shape55<'a> {
    /// ID lines 1-5 (at most 80 characters each).
    pub id_lines: [&'a str; 5],
    /// Load case (record 7).
    pub load_case: u32,
    /// Mode number (record 7).
    pub mode: u32,
    /// Natural frequency, Hz.
    pub f_hz: f64,
    /// Damping ratio (0 when not identified).
    pub damping: f64,
    /// Per node: its number and the x, y, z components.
    pub nodes: &'a [(u32, [Complex64; 3])],
}

/// One dataset 55 (see [`Shape55`]). Refuses non-finite values and over-long ID lines.
pub fn write_dataset55(d: &Shape55<'_>) -> Result<Vec<u8>, UffError> {
    let id = d.mode;
    if d.nodes.is_empty() {
        return Err(UffError::Empty { function_id: id });
    }
    let finite = |c: &Complex64| c.re.is_finite() && c.im.is_finite();
    if let Some(index) = d.nodes.iter().position(|(_, v)| !v.iter().all(finite)) {
        return Err(UffError::NotFinite {
            function_id: id,
            index,
        });
    }
    let w = 2.0 * std::f64::consts::PI * d.f_hz;
    let z = if d.damping.is_finite() {
        d.damping
    } else {
        0.0
    };
    // `+ 0.0`: no negative zero for an undamped mode
    let eig = Complex64::new(-z * w + 0.0, w * (1.0 - z * z).max(0.0).sqrt());
    if !finite(&eig) {
        return Err(UffError::NotFinite {
            function_id: id,
            index: 0,
        });
    }
    let e = |x: f64| fortran_e(x, 13, 5);
    let mut o = format!("{:>6}\n{:>6}{:74}\n", -1, 55, "");
    push_id_lines(&mut o, id, &d.id_lines)?;
    o += &format!("{:>10}{:>10}{:>10}{:>10}{:>10}{:>10}\n", 1, 3, 2, 8, 5, 3);
    o += &format!("{:>10}{:>10}{:>10}{:>10}\n", 2, 6, d.load_case, d.mode);
    o += &format!(
        "{}{}{}{}{}{}\n",
        e(eig.re),
        e(eig.im),
        e(0.0),
        e(0.0),
        e(0.0),
        e(0.0)
    );
    for (node, v) in d.nodes {
        o += &format!("{node:>10}\n");
        for c in v {
            o += &e(c.re);
            o += &e(c.im);
        }
        o.push('\n');
    }
    o += &format!("{:>6}\n", -1);
    Ok(o.into_bytes())
}

/// Refuses a dataset that cannot be written: no values, a non-finite value, a bad abscissa or a
/// direction outside -6..=6.
fn validate(d: &Dataset58<'_>) -> Result<(), UffError> {
    let id = d.function_id;
    if d.values.is_empty() {
        return Err(UffError::Empty { function_id: id });
    }
    if let Some(index) = d
        .values
        .iter()
        .position(|v| !(v.re.is_finite() && v.im.is_finite()))
    {
        return Err(UffError::NotFinite {
            function_id: id,
            index,
        });
    }
    if !(d.f0_hz.is_finite() && d.f0_hz >= 0.0 && d.df_hz.is_finite() && d.df_hz > 0.0) {
        return Err(UffError::Abscissa {
            function_id: id,
            f0_hz: d.f0_hz,
            df_hz: d.df_hz,
        });
    }
    for dof in [d.response, d.reference] {
        if !(-6..=6).contains(&dof.direction) {
            return Err(UffError::Direction {
                function_id: id,
                direction: dof.direction,
            });
        }
    }
    Ok(())
}

/// A text field of dataset `function_id` as written: at most `max` characters on one line,
/// `NONE` when blank.
fn record_text(
    function_id: u32,
    field: &'static str,
    s: &str,
    max: usize,
) -> Result<String, UffError> {
    if s.chars().count() > max || s.contains(['\n', '\r']) {
        return Err(UffError::Text {
            function_id,
            field,
            text: s.to_string(),
            max,
        });
    }
    Ok(if s.trim().is_empty() {
        "NONE".to_string()
    } else {
        s.to_string()
    })
}

/// The five ID lines of dataset `id`, 80 columns each.
fn push_id_lines<S: AsRef<str>>(o: &mut String, id: u32, lines: &[S; 5]) -> Result<(), UffError> {
    const ID_FIELDS: [&str; 5] = [
        "ID line 1",
        "ID line 2",
        "ID line 3",
        "ID line 4",
        "ID line 5",
    ];
    for (line, field) in lines.iter().zip(ID_FIELDS) {
        *o += &format!("{:<80}\n", record_text(id, field, line.as_ref(), 80)?);
    }
    Ok(())
}

/// Records 1-7: the five ID lines, the DOF identification and the data form.
fn push_header_records(o: &mut String, d: &Dataset58<'_>) -> Result<(), UffError> {
    let id = d.function_id;
    push_id_lines(o, id, &d.id_lines)?;
    *o += &format!(
        "{:>5}{:>10}{:>5}{:>10} {:<10}{:>10}{:>4} {:<10}{:>10}{:>4}\n",
        FUNCTION_TYPE_FRF,
        id,
        0,
        0,
        "NONE",
        d.response.node,
        d.response.direction,
        "NONE",
        d.reference.node,
        d.reference.direction
    );
    *o += &format!(
        "{:>10}{:>10}{:>10}{}{}{}\n",
        6,
        d.values.len(),
        1,
        fortran_e(d.f0_hz, 13, 5),
        fortran_e(d.df_hz, 13, 5),
        fortran_e(0.0, 13, 5)
    );
    Ok(())
}

/// Records 8-11: the characteristics of the abscissa, the ordinate numerator and denominator,
/// and the (unused) z axis.
fn push_characteristic_records(o: &mut String, d: &Dataset58<'_>) -> Result<(), UffError> {
    for (axis, what) in [
        (&AxisCharacteristics::frequency(), "abscissa"),
        (&d.numerator, "ordinate numerator"),
        (&d.denominator, "ordinate denominator"),
        (&AxisCharacteristics::unused(), "z axis"),
    ] {
        let (l, f, t) = axis.quantity.exponents();
        *o += &format!(
            "{:>10}{:>5}{:>5}{:>5} {:<20} {:<20}\n",
            axis.quantity.code(),
            l,
            f,
            t,
            record_text(d.function_id, label_field(what, false), &axis.label, 20)?,
            record_text(d.function_id, label_field(what, true), &axis.units, 20)?
        );
    }
    Ok(())
}

/// Record 12: the values, two complex values (four numbers) a line.
fn push_data_records(o: &mut String, d: &Dataset58<'_>) {
    let mut on_line = 0;
    for v in d.values {
        o.push_str(&fortran_e(v.re, 20, 12));
        o.push_str(&fortran_e(v.im, 20, 12));
        on_line += 1;
        if on_line == 2 {
            o.push('\n');
            on_line = 0;
        }
    }
    if on_line != 0 {
        o.push('\n');
    }
}

fn label_field(axis: &'static str, units: bool) -> &'static str {
    match (axis, units) {
        ("abscissa", false) => "abscissa label",
        ("abscissa", true) => "abscissa units",
        ("ordinate numerator", false) => "ordinate numerator label",
        ("ordinate numerator", true) => "ordinate numerator units",
        ("ordinate denominator", false) => "ordinate denominator label",
        ("ordinate denominator", true) => "ordinate denominator units",
        (_, false) => "z-axis label",
        (_, true) => "z-axis units",
    }
}

/// Fortran `Ew.d`: `d` digits after the point, a signed exponent of at least two digits,
/// right-aligned in `w` columns (e.g. `fortran_e(0.1, 13, 5)` is `"  1.00000e-01"`).
fn fortran_e(x: f64, width: usize, decimals: usize) -> String {
    let s = format!("{x:.decimals$e}");
    let (mantissa, exp) = s.split_once('e').unwrap_or((&s, "0"));
    let exp: i32 = exp.parse().unwrap_or(0);
    let sign = if exp < 0 { '-' } else { '+' };
    format!(
        "{:>width$}",
        format!("{mantissa}e{sign}{:02}", exp.unsigned_abs())
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A minimal reader of what [`write_dataset58`] writes, by the format's fixed columns.
    #[derive(Debug)]
    struct Read58 {
        id1: String,
        header6: (u32, u32, u32, u32, u32, i32, u32, i32),
        ord_type: u32,
        n: usize,
        spacing: u32,
        f0: f64,
        df: f64,
        chars: Vec<(i32, i32, i32, i32, String, String)>,
        values: Vec<Complex64>,
    }

    fn col<T: std::str::FromStr>(line: &str, from: usize, to: usize) -> T
    where
        T::Err: std::fmt::Debug,
    {
        line[from..to.min(line.len())].trim().parse().unwrap()
    }

    fn read(text: &str) -> Vec<Read58> {
        let lines: Vec<&str> = text.lines().collect();
        let mut out = Vec::new();
        let mut i = 0;
        while i < lines.len() {
            assert_eq!(lines[i], "    -1");
            assert_eq!(lines[i + 1], "    58");
            let h = &lines[i + 2..i + 13];
            for l in &h[..5] {
                assert_eq!(l.len(), 80);
            }
            let r6 = h[5];
            let r7 = h[6];
            let n: usize = col(r7, 10, 20);
            let chars = h[7..11]
                .iter()
                .map(|l| {
                    (
                        col(l, 0, 10),
                        col(l, 10, 15),
                        col(l, 15, 20),
                        col(l, 20, 25),
                        l[26..46].trim().to_string(),
                        l[47..].trim().to_string(),
                    )
                })
                .collect();
            let mut values = Vec::new();
            let mut j = i + 13;
            while lines[j] != "    -1" {
                let l = lines[j];
                assert!(l.len().is_multiple_of(40) && l.len() <= 80, "{l:?}");
                for k in 0..l.len() / 40 {
                    values.push(Complex64::new(
                        col(l, 40 * k, 40 * k + 20),
                        col(l, 40 * k + 20, 40 * k + 40),
                    ));
                }
                j += 1;
            }
            out.push(Read58 {
                id1: h[0].trim().to_string(),
                header6: (
                    col(r6, 0, 5),
                    col(r6, 5, 15),
                    col(r6, 15, 20),
                    col(r6, 20, 30),
                    col(r6, 41, 51),
                    col(r6, 51, 55),
                    col(r6, 66, 76),
                    col(r6, 76, 80),
                ),
                ord_type: col(r7, 0, 10),
                n,
                spacing: col(r7, 20, 30),
                f0: col(r7, 30, 43),
                df: col(r7, 43, 56),
                chars,
                values,
            });
            i = j + 1;
        }
        out
    }

    #[test]
    fn fortran_e_matches_printf() {
        // The strings C's printf("%13.5e") / ("%20.12e") gives for these values.
        assert_eq!(fortran_e(0.1, 13, 5), "  1.00000e-01");
        assert_eq!(fortran_e(0.0, 13, 5), "  0.00000e+00");
        assert_eq!(fortran_e(2048.0, 13, 5), "  2.04800e+03");
        assert_eq!(fortran_e(-2.5e-7, 20, 12), " -2.500000000000e-07");
        assert_eq!(
            fortran_e(68.043_478_260_869_57, 20, 12),
            "  6.804347826087e+01"
        );
        assert_eq!(fortran_e(1e-100, 20, 12), " 1.000000000000e-100");
    }

    #[test]
    fn round_trip_through_the_fixed_columns() {
        let acc: Vec<Complex64> = (0..5)
            .map(|k| Complex64::new(1.0 + k as f64 * 0.37, -1e-3 * k as f64))
            .collect();
        let tgt: Vec<Complex64> = (0..4)
            .map(|k| Complex64::new(-68.04347826087 * k as f64, 1.5e-9))
            .collect();
        let input = Dof {
            node: 100,
            direction: 3,
        };
        let datasets = [
            Dataset58::acceleration_frf(
                "tip accelerometer",
                1,
                Dof {
                    node: 0,
                    direction: 3,
                },
                input,
                0.0,
                0.1,
                &acc,
            ),
            Dataset58::acceleration_frf(
                "vision target 3",
                2,
                Dof {
                    node: 3,
                    direction: 3,
                },
                input,
                5.0,
                0.1,
                &tgt,
            ),
        ];
        let bytes = write_file(&datasets).unwrap();
        let text = String::from_utf8(bytes).unwrap();
        let back = read(&text);
        assert_eq!(back.len(), 2);
        for (d, r) in datasets.iter().zip(&back) {
            assert_eq!(r.id1, d.id_lines[0]);
            assert_eq!(
                r.header6,
                (4, d.function_id, 0, 0, d.response.node, 3, 100, 3)
            );
            assert_eq!((r.ord_type, r.n, r.spacing), (6, d.values.len(), 1));
            assert_eq!((r.f0, r.df), (d.f0_hz, 0.1));
            assert_eq!(r.chars[0], (18, 0, 0, 0, "Frequency".into(), "Hz".into()));
            assert_eq!(
                r.chars[1],
                (12, 1, 0, 0, "Acceleration".into(), "m/s^2".into())
            );
            assert_eq!(r.chars[2], r.chars[1]);
            assert_eq!(r.chars[3], (0, 0, 0, 0, "NONE".into(), "NONE".into()));
            assert_eq!(r.values.len(), d.values.len());
            for (a, b) in r.values.iter().zip(d.values) {
                // 13 significant digits (E20.12): relative error below 5e-13.
                assert!((a - b).norm() <= 5e-13 * b.norm(), "{a} vs {b}");
            }
        }
        // Odd count: the last line holds one value (40 columns).
        assert!(text.contains("\n    -1\n    -1\n    58\n"));
    }

    #[test]
    fn bad_datasets_name_the_function() {
        let v = [Complex64::new(f64::NAN, 0.0)];
        let dof = Dof {
            node: 1,
            direction: 3,
        };
        let e = write_dataset58(&Dataset58::acceleration_frf("x", 7, dof, dof, 0.0, 0.1, &v))
            .unwrap_err();
        assert_eq!(
            e,
            UffError::NotFinite {
                function_id: 7,
                index: 0
            }
        );
        let ok = [Complex64::new(1.0, 0.0)];
        let long = "x".repeat(81);
        let e = write_dataset58(&Dataset58::acceleration_frf(
            &long, 8, dof, dof, 0.0, 0.1, &ok,
        ))
        .unwrap_err();
        assert!(e.to_string().contains("function 8: ID line 1"), "{e}");
        let e = write_dataset58(&Dataset58::acceleration_frf(
            "x", 9, dof, dof, 0.0, 0.0, &ok,
        ))
        .unwrap_err();
        assert!(matches!(e, UffError::Abscissa { function_id: 9, .. }));
        let e = write_dataset58(&Dataset58::acceleration_frf(
            "x",
            9,
            dof,
            dof,
            0.0,
            0.1,
            &[],
        ))
        .unwrap_err();
        assert_eq!(e, UffError::Empty { function_id: 9 });
    }
}
