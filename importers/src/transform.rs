//! 4x4 transforms as the Alembic and USD importers compose them: f64, as both
//! formats store them, acting on column vectors (`p' = m · [p, 1]`). Files
//! that store matrices for row vectors (Imath, USD) are transposed on reading.

pub(crate) type Matrix = [[f64; 4]; 4];

pub(crate) const IDENTITY: Matrix = [
    [1.0, 0.0, 0.0, 0.0],
    [0.0, 1.0, 0.0, 0.0],
    [0.0, 0.0, 1.0, 0.0],
    [0.0, 0.0, 0.0, 1.0],
];

pub(crate) fn translation(v: [f64; 3]) -> Matrix {
    let mut m = IDENTITY;
    m[0][3] = v[0];
    m[1][3] = v[1];
    m[2][3] = v[2];
    m
}

pub(crate) fn scaling(v: [f64; 3]) -> Matrix {
    let mut m = IDENTITY;
    m[0][0] = v[0];
    m[1][1] = v[1];
    m[2][2] = v[2];
    m
}

/// The product `a · b`: `b` applies first.
pub(crate) fn multiply(a: &Matrix, b: &Matrix) -> Matrix {
    let mut m = [[0.0; 4]; 4];
    for (r, row) in m.iter_mut().enumerate() {
        for (c, cell) in row.iter_mut().enumerate() {
            *cell = (0..4).map(|k| a[r][k] * b[k][c]).sum();
        }
    }
    m
}

pub(crate) fn transform_point(m: &Matrix, p: [f64; 3]) -> [f64; 3] {
    let mut out = [0.0; 3];
    for (r, value) in out.iter_mut().enumerate() {
        *value = m[r][0] * p[0] + m[r][1] * p[1] + m[r][2] * p[2] + m[r][3];
    }
    out
}

/// Gauss-Jordan inverse with partial pivoting; `None` when singular.
pub(crate) fn invert(m: &Matrix) -> Option<Matrix> {
    let mut a = *m;
    let mut inv = IDENTITY;
    for col in 0..4 {
        let pivot = (col..4).max_by(|&x, &y| a[x][col].abs().total_cmp(&a[y][col].abs()))?;
        if a[pivot][col].abs() < 1e-300 {
            return None;
        }
        a.swap(col, pivot);
        inv.swap(col, pivot);
        let d = a[col][col];
        for k in 0..4 {
            a[col][k] /= d;
            inv[col][k] /= d;
        }
        for row in 0..4 {
            if row != col {
                let f = a[row][col];
                for k in 0..4 {
                    a[row][k] -= f * a[col][k];
                    inv[row][k] -= f * inv[col][k];
                }
            }
        }
    }
    Some(inv)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn translation_is_the_last_column_and_the_right_factor_applies_first() {
        let translate = translation([1.0, 2.0, 3.0]);
        let scale = scaling([2.0; 3]);
        assert_eq!(
            transform_point(&translate, [1.0, 1.0, 1.0]),
            [2.0, 3.0, 4.0]
        );
        let scale_then_translate = multiply(&translate, &scale);
        assert_eq!(
            transform_point(&scale_then_translate, [1.0, 1.0, 1.0]),
            [3.0, 4.0, 5.0]
        );
    }
}
