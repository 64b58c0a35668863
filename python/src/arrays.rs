//! numpy in and out: one row or a batch of rows, `float64`, read in place when the array is
//! C-contiguous `float64` (copied into row-major data otherwise).

use std::borrow::Cow;

use numpy::ndarray::{ArrayD, IxDyn};
use numpy::{AllowTypeChange, IntoPyArray, PyArrayDyn, PyArrayLikeDyn};
use pyo3::prelude::*;

use crate::errors::input;

/// An array-like of rows of `width` values: `(width,)` is one row (`batch` is `None`), `(N, width)` a
/// batch of N. Non-finite values are refused, naming the argument, the row and the column.
pub struct Rows<'a> {
    /// Row-major values, `len = rows × width`: the array's own buffer when it is C-contiguous.
    pub data: Cow<'a, [f64]>,
    /// `Some(N)` for a batch.
    pub batch: Option<usize>,
}

impl<'a> Rows<'a> {
    /// Reads `value` as rows of `width`, named `what` in errors.
    pub fn read(value: &'a PyArrayLikeDyn<'_, f64, AllowTypeChange>, width: usize, what: &str) -> PyResult<Rows<'a>> {
        Self::read_shaped(value, &[width], what)
    }

    /// Reads `value` as items of shape `item` (e.g. `[4, 4]` for poses): exactly that shape is one item,
    /// one more leading axis a batch.
    pub fn read_shaped(
        value: &'a PyArrayLikeDyn<'_, f64, AllowTypeChange>,
        item: &[usize],
        what: &str,
    ) -> PyResult<Rows<'a>> {
        let view = value.as_array();
        let shape = view.shape().to_vec();
        let batch = if shape == item {
            None
        } else if shape.len() == item.len() + 1 && shape[1..] == *item {
            Some(shape[0])
        } else {
            return Err(input(format!(
                "{what}: expected shape {} or {}, got {}",
                tuple(item),
                tuple(&[&[usize::MAX][..], item].concat()),
                tuple(&shape)
            )));
        };
        // A batch is read where numpy holds it (the GIL is released while it is read, as numpy's own
        // loops do: an array mutated meanwhile from another Python thread is the caller's race).
        let data: Cow<'a, [f64]> = match value.as_slice() {
            Ok(slice) => Cow::Borrowed(slice),
            Err(_) => Cow::Owned(view.iter().copied().collect()),
        };
        let per: usize = item.iter().product();
        if let Some(i) = data.iter().position(|v| !v.is_finite()) {
            let (row, col) = (i / per.max(1), i % per.max(1));
            return Err(input(match batch {
                Some(_) => format!("{what}: row {row}, value {col} is not finite ({})", data[i]),
                None => format!("{what}: value {col} is not finite ({})", data[i]),
            }));
        }
        Ok(Rows { data, batch })
    }

    /// Number of items (1 for a single one).
    pub fn count(&self) -> usize {
        self.batch.unwrap_or(1)
    }
}

/// A shape as Python prints it: `(6,)`, `(4, 4)`; `usize::MAX` stands for `N`.
fn tuple(shape: &[usize]) -> String {
    let dims: Vec<String> =
        shape.iter().map(|&d| if d == usize::MAX { "N".to_string() } else { d.to_string() }).collect();
    if dims.len() == 1 { format!("({},)", dims[0]) } else { format!("({})", dims.join(", ")) }
}

/// `data` as an array of `item` shape, with a leading batch axis when `batch` is `Some`.
pub fn output<'py>(
    py: Python<'py>,
    data: Vec<f64>,
    batch: Option<usize>,
    item: &[usize],
) -> PyResult<Bound<'py, PyArrayDyn<f64>>> {
    let mut shape = Vec::with_capacity(item.len() + 1);
    if let Some(n) = batch {
        shape.push(n);
    }
    shape.extend_from_slice(item);
    let array =
        ArrayD::from_shape_vec(IxDyn(&shape), data).map_err(|e| crate::errors::raise(crate::errors::Kind::Other, e))?;
    Ok(array.into_pyarray(py))
}
