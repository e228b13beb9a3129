//! NumPy `.npy` files: the one reader and writer of the workspace.
//!
//! - [`read_npy`] / [`write_npy`]: 2-D map layers of one element type (`u8`, `u16`,
//!   `i32`, `f32`, `bool`) as [`Grid`]s.
//! - [`nd`]: arrays of any shape with the dtype found in the file kept
//!   ([`read_array`]), streamed windows of large feature arrays, and
//!   [`fortran_to_c`].
//!
//! Built on the `npyz` crate: it parses the header (dtype, shape, order), converts
//! endianness, and checks that the stored dtype matches the requested element type.
//! This module adds what the map layers need on top: 2-D shape checks, Fortran-order
//! arrays transposed into row-major [`Grid`]s, and errors that name the file.

use std::fs::File;
use std::io::{BufReader, BufWriter, Read, Write};
use std::path::{Path, PathBuf};

use npyz::WriterBuilder;

use crate::grid::Grid;

pub mod nd;

pub use nd::{fortran_to_c, read_array, write_array, NdArray, NdData};

/// Element types a layer file may hold.
pub trait NpyElement: npyz::Deserialize + npyz::AutoSerialize + Copy + Default {}
impl NpyElement for u8 {}
impl NpyElement for u16 {}
impl NpyElement for i32 {}
impl NpyElement for f32 {}
impl NpyElement for bool {}

/// Why a `.npy` layer could not be read or written.
#[derive(Debug, thiserror::Error)]
pub enum NpyError {
    /// Opening, parsing, reading or writing the file failed, or its data ends early.
    #[error("{path}: {source}")]
    Io {
        /// The file concerned.
        path: PathBuf,
        /// The underlying I/O error.
        #[source]
        source: std::io::Error,
    },
    /// The file holds an array that is not 2-D.
    #[error("{path}: expected a 2-D array, found shape {shape:?}")]
    NotTwoD {
        /// The file concerned.
        path: PathBuf,
        /// The shape found in the header.
        shape: Vec<u64>,
    },
    /// The stored dtype does not match the requested element type.
    #[error("{path}: dtype {found} does not hold {wanted} values")]
    DType {
        /// The file concerned.
        path: PathBuf,
        /// The dtype string found in the header, e.g. `<f4`.
        found: String,
        /// The Rust element type asked for.
        wanted: &'static str,
    },
    /// The array's element count overflows `usize`.
    #[error("{path}: array of shape {shape:?} is too large")]
    TooLarge {
        /// The file concerned.
        path: PathBuf,
        /// The shape found in the header.
        shape: Vec<u64>,
    },
    /// The file does not start with a `.npy` header.
    #[error("{}: not a .npy file: {message}", path.display())]
    NotNpy {
        /// The file concerned.
        path: PathBuf,
        /// What the header parser reported.
        message: String,
    },
    /// The array's shape, size or dtype is not what the reader takes.
    #[error("{}: {message}", path.display())]
    Array {
        /// The file concerned.
        path: PathBuf,
        /// What is wrong with the array.
        message: String,
    },
}

fn io_err(path: &Path) -> impl FnOnce(std::io::Error) -> NpyError + '_ {
    move |source| NpyError::Io {
        path: path.to_path_buf(),
        source,
    }
}

/// Read a 2-D `.npy` file into a row-major grid (row = first axis).
pub fn read_npy<T: NpyElement>(path: impl AsRef<Path>) -> Result<Grid<T>, NpyError> {
    let path = path.as_ref();
    let file = File::open(path).map_err(io_err(path))?;
    read_npy_from(BufReader::new(file), path)
}

/// Read a 2-D `.npy` array from any reader; `path` only names the source in errors.
pub fn read_npy_from<T: NpyElement>(reader: impl Read, path: &Path) -> Result<Grid<T>, NpyError> {
    let npy = npyz::NpyFile::new(reader).map_err(io_err(path))?;
    let shape = npy.shape().to_vec();
    let order = npy.order();
    if shape.len() != 2 {
        return Err(NpyError::NotTwoD {
            path: path.to_path_buf(),
            shape,
        });
    }
    let too_large = || NpyError::TooLarge {
        path: path.to_path_buf(),
        shape: shape.clone(),
    };
    let rows = usize::try_from(shape[0]).map_err(|_| too_large())?;
    let cols = usize::try_from(shape[1]).map_err(|_| too_large())?;
    rows.checked_mul(cols).ok_or_else(too_large)?;
    let found = npy.dtype().descr();
    let reader = npy.data::<T>().map_err(|_| NpyError::DType {
        path: path.to_path_buf(),
        found,
        wanted: std::any::type_name::<T>(),
    })?;
    let data = reader
        .collect::<std::io::Result<Vec<T>>>()
        .map_err(io_err(path))?;
    let data = match order {
        npyz::Order::C => data,
        npyz::Order::Fortran => {
            // column-major on disk: element (r, c) sits at c * rows + r
            let mut out = vec![T::default(); data.len()];
            for (i, v) in data.into_iter().enumerate() {
                let (c, r) = (i / rows.max(1), i % rows.max(1));
                if let Some(slot) = out.get_mut(r * cols + c) {
                    *slot = v;
                }
            }
            out
        }
    };
    Grid::from_vec(rows, cols, data).ok_or_else(|| NpyError::Io {
        path: path.to_path_buf(),
        source: std::io::Error::new(
            std::io::ErrorKind::UnexpectedEof,
            "fewer elements than the shape says",
        ),
    })
}

/// Write a grid as a C-order 2-D `.npy` file.
pub fn write_npy<T: NpyElement>(path: impl AsRef<Path>, grid: &Grid<T>) -> Result<(), NpyError> {
    let path = path.as_ref();
    let file = File::create(path).map_err(io_err(path))?;
    let mut w = BufWriter::new(file);
    write_npy_to(&mut w, grid).map_err(io_err(path))?;
    w.flush().map_err(io_err(path))
}

/// Write a grid as a C-order 2-D `.npy` array to any writer.
pub fn write_npy_to<T: NpyElement>(writer: impl Write, grid: &Grid<T>) -> std::io::Result<()> {
    let shape = [grid.rows() as u64, grid.cols() as u64];
    let mut w = npyz::WriteOptions::new()
        .default_dtype()
        .shape(&shape)
        .writer(writer)
        .begin_nd()?;
    w.extend(grid.as_slice().iter().copied())?;
    w.finish()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn roundtrip<T: NpyElement + PartialEq + std::fmt::Debug>(g: &Grid<T>) {
        let mut buf = Vec::new();
        write_npy_to(&mut buf, g).unwrap();
        let back: Grid<T> = read_npy_from(&buf[..], Path::new("mem.npy")).unwrap();
        assert_eq!(&back, g);
    }

    #[test]
    fn roundtrips_all_layer_types() {
        roundtrip(&Grid::from_vec(2, 3, vec![0u8, 1, 2, 3, 4, 255]).unwrap());
        roundtrip(&Grid::from_vec(3, 2, vec![0u16, 1, 2, 3, 4, 65535]).unwrap());
        roundtrip(&Grid::from_vec(1, 3, vec![-1i32, 0, i32::MAX]).unwrap());
        roundtrip(&Grid::from_vec(2, 2, vec![0.5f32, -1.0, f32::INFINITY, 3.25]).unwrap());
        roundtrip(&Grid::from_vec(1, 2, vec![true, false]).unwrap());
    }

    #[test]
    fn wrong_dtype_and_shape_are_errors_naming_the_file() {
        let mut buf = Vec::new();
        write_npy_to(&mut buf, &Grid::from_vec(1, 2, vec![1.0f32, 2.0]).unwrap()).unwrap();
        let err = read_npy_from::<u8>(&buf[..], Path::new("layer.npy")).unwrap_err();
        assert!(matches!(err, NpyError::DType { .. }), "{err}");
        assert!(err.to_string().contains("layer.npy"));

        let mut buf = Vec::new();
        npyz::WriteOptions::new()
            .default_dtype()
            .shape(&[2, 2, 2])
            .writer(&mut buf)
            .begin_nd()
            .unwrap()
            .extend(0u8..8)
            .unwrap();
        let err = read_npy_from::<u8>(&buf[..], Path::new("cube.npy")).unwrap_err();
        assert!(matches!(err, NpyError::NotTwoD { .. }), "{err}");
    }

    #[test]
    fn fortran_order_is_transposed_into_rows() {
        let mut buf = Vec::new();
        let mut w = npyz::WriteOptions::new()
            .default_dtype()
            .order(npyz::Order::Fortran)
            .shape(&[2, 3])
            .writer(&mut buf)
            .begin_nd()
            .unwrap();
        // column-major: (0,0) (1,0) (0,1) (1,1) (0,2) (1,2)
        w.extend([0u8, 10, 1, 11, 2, 12]).unwrap();
        w.finish().unwrap();
        let g: Grid<u8> = read_npy_from(&buf[..], Path::new("f.npy")).unwrap();
        assert_eq!(g.as_slice(), &[0, 1, 2, 10, 11, 12]);
    }

    #[test]
    fn missing_file_names_the_path() {
        let err = read_npy::<u8>("/nonexistent/dir/x.npy").unwrap_err();
        assert!(err.to_string().contains("/nonexistent/dir/x.npy"));
    }
}
