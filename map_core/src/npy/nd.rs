//! N-dimensional `.npy` arrays for depth frames and VLMaps' layers (`H x W`,
//! `H x W x 3`, `H x W x C`), with the dtype found in the file kept, so that callers
//! can accept several dtypes and say what they expected and what they found.
//!
//! Built on `npyz` (header parsing, endianness). [`super::read_npy`] reads the map's
//! 2-D layers of one fixed element type; this reads any shape and the common dtypes.

use std::fs::File;
use std::io::{BufReader, BufWriter, Seek, Write};
use std::path::Path;

use npyz::{TypeChar, WriterBuilder};

use super::NpyError;

/// Largest array [`read_array`] loads whole (elements); larger ones are streamed.
pub const MAX_WHOLE_ELEMENTS: usize = 1 << 28;

/// The elements of an array, in C (row-major) order whatever the file's order.
#[derive(Debug, Clone, PartialEq)]
pub enum NdData {
    /// Booleans (`b1`).
    Bool(Vec<bool>),
    /// 8-bit signed integers (`i1`).
    I8(Vec<i8>),
    /// 8-bit unsigned integers (`u1`).
    U8(Vec<u8>),
    /// 16-bit unsigned integers (`u2`).
    U16(Vec<u16>),
    /// 32-bit unsigned integers (`u4`).
    U32(Vec<u32>),
    /// 64-bit unsigned integers (`u8`).
    U64(Vec<u64>),
    /// 16-bit signed integers (`i2`).
    I16(Vec<i16>),
    /// 32-bit signed integers (`i4`).
    I32(Vec<i32>),
    /// 64-bit signed integers (`i8`).
    I64(Vec<i64>),
    /// 32-bit floats (`f4`).
    F32(Vec<f32>),
    /// 64-bit floats (`f8`).
    F64(Vec<f64>),
}

/// An array read from a `.npy` file.
#[derive(Debug, Clone, PartialEq)]
pub struct NdArray {
    /// Length of each axis, outermost first.
    pub shape: Vec<usize>,
    /// The file's dtype string, e.g. `<f4`.
    pub dtype: String,
    /// The elements, in C (row-major) order.
    pub data: NdData,
}

impl NdArray {
    /// Every element as `f64` (exact for all supported dtypes but 64-bit integers
    /// beyond 2^53), bools as 0/1.
    pub fn to_f64(&self) -> Vec<f64> {
        match &self.data {
            NdData::Bool(v) => v.iter().map(|&b| f64::from(u8::from(b))).collect(),
            NdData::I8(v) => v.iter().map(|&x| f64::from(x)).collect(),
            NdData::U8(v) => v.iter().map(|&x| f64::from(x)).collect(),
            NdData::U16(v) => v.iter().map(|&x| f64::from(x)).collect(),
            NdData::U32(v) => v.iter().map(|&x| f64::from(x)).collect(),
            NdData::U64(v) => v.iter().map(|&x| x as f64).collect(),
            NdData::I16(v) => v.iter().map(|&x| f64::from(x)).collect(),
            NdData::I32(v) => v.iter().map(|&x| f64::from(x)).collect(),
            NdData::I64(v) => v.iter().map(|&x| x as f64).collect(),
            NdData::F32(v) => v.iter().map(|&x| f64::from(x)).collect(),
            NdData::F64(v) => v.clone(),
        }
    }

    /// Shape as numpy prints it: `(120, 160, 3)`.
    pub fn shape_str(&self) -> String {
        shape_str(&self.shape)
    }
}

/// `(a, b, c)`, numpy's spelling of a shape (`(a,)` for one axis).
pub fn shape_str(shape: &[usize]) -> String {
    match shape {
        [one] => format!("({one},)"),
        _ => format!(
            "({})",
            shape
                .iter()
                .map(|d| d.to_string())
                .collect::<Vec<_>>()
                .join(", ")
        ),
    }
}

use super::io_err;

fn array_err(path: &Path, message: String) -> NpyError {
    NpyError::Array {
        path: path.to_path_buf(),
        message,
    }
}

/// Open a `.npy` file and check its shape fits in memory; returns the reader and shape.
fn open(path: &Path) -> Result<(npyz::NpyFile<BufReader<File>>, Vec<usize>), NpyError> {
    let file = File::open(path).map_err(io_err(path))?;
    let npy = npyz::NpyFile::new(BufReader::new(file)).map_err(|e| NpyError::NotNpy {
        path: path.to_path_buf(),
        message: e.to_string(),
    })?;
    let mut shape = Vec::with_capacity(npy.shape().len());
    let mut total: usize = 1;
    for &d in npy.shape() {
        let d = usize::try_from(d).ok();
        match d.and_then(|d| total.checked_mul(d).map(|t| (d, t))) {
            Some((d, t)) => {
                shape.push(d);
                total = t;
            }
            None => {
                return Err(array_err(
                    path,
                    format!("array of shape {:?} is too large", npy.shape()),
                ))
            }
        }
    }
    Ok((npy, shape))
}

/// The shape of the array in a `.npy` file, from its header alone.
pub fn read_shape(path: &Path) -> Result<Vec<usize>, NpyError> {
    open(path).map(|(_, shape)| shape)
}

/// Read a whole array (at most [`MAX_WHOLE_ELEMENTS`] elements).
pub fn read_array(path: &Path) -> Result<NdArray, NpyError> {
    let (npy, shape) = open(path)?;
    let total: usize = shape.iter().product();
    if total > MAX_WHOLE_ELEMENTS {
        return Err(array_err(
            path,
            format!(
                "array of shape {} has {total} elements, more than the {MAX_WHOLE_ELEMENTS} read at once",
                shape_str(&shape)
            ),
        ));
    }
    let order = npy.order();
    let dtype_s = npy.dtype().descr();
    let ts = match npy.dtype() {
        npyz::DType::Plain(ts) => ts,
        _ => {
            return Err(array_err(
                path,
                format!("structured dtype {dtype_s} is not supported"),
            ))
        }
    };
    let dtype = ts.to_string();
    let unsupported = || {
        array_err(
            path,
            format!(
                "dtype {dtype} is not supported (bool, int8/16/32/64, uint8/16/32/64, float32/64 are)"
            ),
        )
    };
    let data = match (ts.type_char(), ts.size_field()) {
        (TypeChar::Bool, 1) => NdData::Bool(npy.into_vec().map_err(io_err(path))?),
        (TypeChar::Int, 1) => NdData::I8(npy.into_vec().map_err(io_err(path))?),
        (TypeChar::Uint, 1) => NdData::U8(npy.into_vec().map_err(io_err(path))?),
        (TypeChar::Uint, 2) => NdData::U16(npy.into_vec().map_err(io_err(path))?),
        (TypeChar::Uint, 4) => NdData::U32(npy.into_vec().map_err(io_err(path))?),
        (TypeChar::Uint, 8) => NdData::U64(npy.into_vec().map_err(io_err(path))?),
        (TypeChar::Int, 2) => NdData::I16(npy.into_vec().map_err(io_err(path))?),
        (TypeChar::Int, 4) => NdData::I32(npy.into_vec().map_err(io_err(path))?),
        (TypeChar::Int, 8) => NdData::I64(npy.into_vec().map_err(io_err(path))?),
        (TypeChar::Float, 4) => NdData::F32(npy.into_vec().map_err(io_err(path))?),
        (TypeChar::Float, 8) => NdData::F64(npy.into_vec().map_err(io_err(path))?),
        _ => return Err(unsupported()),
    };
    let data = match order {
        npyz::Order::C => data,
        npyz::Order::Fortran => match data {
            NdData::Bool(v) => NdData::Bool(fortran_to_c(&v, &shape)),
            NdData::I8(v) => NdData::I8(fortran_to_c(&v, &shape)),
            NdData::U8(v) => NdData::U8(fortran_to_c(&v, &shape)),
            NdData::U16(v) => NdData::U16(fortran_to_c(&v, &shape)),
            NdData::U32(v) => NdData::U32(fortran_to_c(&v, &shape)),
            NdData::U64(v) => NdData::U64(fortran_to_c(&v, &shape)),
            NdData::I16(v) => NdData::I16(fortran_to_c(&v, &shape)),
            NdData::I32(v) => NdData::I32(fortran_to_c(&v, &shape)),
            NdData::I64(v) => NdData::I64(fortran_to_c(&v, &shape)),
            NdData::F32(v) => NdData::F32(fortran_to_c(&v, &shape)),
            NdData::F64(v) => NdData::F64(fortran_to_c(&v, &shape)),
        },
    };
    let len = match &data {
        NdData::Bool(v) => v.len(),
        NdData::I8(v) => v.len(),
        NdData::U8(v) => v.len(),
        NdData::U16(v) => v.len(),
        NdData::U32(v) => v.len(),
        NdData::U64(v) => v.len(),
        NdData::I16(v) => v.len(),
        NdData::I32(v) => v.len(),
        NdData::I64(v) => v.len(),
        NdData::F32(v) => v.len(),
        NdData::F64(v) => v.len(),
    };
    if len != total {
        return Err(array_err(
            path,
            format!(
                "the file holds {len} elements, shape {} says {total}",
                shape_str(&shape)
            ),
        ));
    }
    Ok(NdArray { shape, dtype, data })
}

/// Permute column-major (numpy `order='F'`) data of `shape` into row-major order.
///
/// ```
/// // [[1, 2, 3], [4, 5, 6]] stored first axis fastest
/// assert_eq!(map_core::npy::fortran_to_c(&[1, 4, 2, 5, 3, 6], &[2, 3]), vec![1, 2, 3, 4, 5, 6]);
/// ```
pub fn fortran_to_c<T: Copy + Default>(data: &[T], shape: &[usize]) -> Vec<T> {
    let mut out = vec![T::default(); data.len()];
    let n = shape.len();
    let mut idx = vec![0usize; n];
    // Walk the Fortran data in its own order (first axis fastest) and place each
    // element at its C offset.
    for &v in data {
        let mut off = 0usize;
        for (k, &i) in idx.iter().enumerate() {
            off = off * shape[k] + i;
        }
        if let Some(slot) = out.get_mut(off) {
            *slot = v;
        }
        for k in 0..n {
            idx[k] += 1;
            if idx[k] < shape[k] {
                break;
            }
            idx[k] = 0;
        }
    }
    out
}

/// A window of an `H x W x C` float array, read by seeking row by row so that only
/// the window is held in memory (VLMaps' 1000 x 1000 x 512 feature grids are 2 GB).
/// Returns `(C, data)` with `data` row-major `[row][col][channel]` as `f32`.
pub fn read_hwc_window_f32(
    path: &Path,
    row0: usize,
    rows: usize,
    col0: usize,
    cols: usize,
) -> Result<(Vec<usize>, usize, Vec<f32>), NpyError> {
    let (npy, shape) = open(path)?;
    let dtype = npy.dtype().descr();
    if shape.len() != 3 {
        return Err(array_err(
            path,
            format!(
                "expected a 3-D array (H, W, C) of float32, found shape {}",
                shape_str(&shape)
            ),
        ));
    }
    let (h, w, c) = (shape[0], shape[1], shape[2]);
    if row0 + rows > h || col0 + cols > w {
        return Err(array_err(
            path,
            format!(
                "window rows {row0}..{} cols {col0}..{} lies outside shape {}",
                row0 + rows,
                col0 + cols,
                shape_str(&shape)
            ),
        ));
    }
    if npy.order() == npyz::Order::Fortran && (h > 1 || w > 1) {
        return Err(array_err(
            path,
            "Fortran-order feature arrays are not supported; save with np.ascontiguousarray".into(),
        ));
    }
    let n = rows
        .checked_mul(cols)
        .and_then(|x| x.checked_mul(c))
        .filter(|&x| x <= MAX_WHOLE_ELEMENTS * 4)
        .ok_or_else(|| {
            array_err(
                path,
                format!("a {rows} x {cols} x {c} window is too large to load; crop it"),
            )
        })?;
    let mut out = Vec::with_capacity(n);
    match npy.dtype() {
        npyz::DType::Plain(ts) if ts.type_char() == TypeChar::Float && ts.size_field() == 4 => {
            let r = npy
                .data::<f32>()
                .map_err(|e| array_err(path, e.to_string()))?;
            read_window(r, &mut out, w, c, row0, rows, col0, cols, |x| x).map_err(io_err(path))?;
        }
        npyz::DType::Plain(ts) if ts.type_char() == TypeChar::Float && ts.size_field() == 8 => {
            let r = npy
                .data::<f64>()
                .map_err(|e| array_err(path, e.to_string()))?;
            read_window(r, &mut out, w, c, row0, rows, col0, cols, |x| x as f32)
                .map_err(io_err(path))?;
        }
        _ => {
            return Err(array_err(
                path,
                format!("expected dtype float32 (or float64), found {dtype}"),
            ))
        }
    }
    Ok((shape, c, out))
}

#[allow(clippy::too_many_arguments)] // one window, spelled out
fn read_window<T: npyz::Deserialize, R: std::io::Read + Seek>(
    mut r: npyz::NpyReader<T, R>,
    out: &mut Vec<f32>,
    w: usize,
    c: usize,
    row0: usize,
    rows: usize,
    col0: usize,
    cols: usize,
    conv: impl Fn(T) -> f32,
) -> std::io::Result<()> {
    let short = || std::io::Error::new(std::io::ErrorKind::UnexpectedEof, "file ends early");
    let full_rows = col0 == 0 && cols == w;
    if full_rows {
        r.seek_to((row0 * w * c) as u64)?;
        for _ in 0..rows * cols * c {
            out.push(conv(r.next().ok_or_else(short)??));
        }
        return Ok(());
    }
    for row in row0..row0 + rows {
        r.seek_to(((row * w + col0) * c) as u64)?;
        for _ in 0..cols * c {
            out.push(conv(r.next().ok_or_else(short)??));
        }
    }
    Ok(())
}

/// Element types [`write_array`] writes.
pub trait NdElement: npyz::AutoSerialize + Copy {}
impl NdElement for u8 {}
impl NdElement for u16 {}
impl NdElement for f32 {}

/// Write a C-order array of any shape.
pub fn write_array<T: NdElement>(path: &Path, shape: &[usize], data: &[T]) -> Result<(), NpyError> {
    let file = File::create(path).map_err(io_err(path))?;
    let mut w = BufWriter::new(file);
    let shape_u64: Vec<u64> = shape.iter().map(|&d| d as u64).collect();
    (|| -> std::io::Result<()> {
        let mut npy = npyz::WriteOptions::new()
            .default_dtype()
            .shape(&shape_u64)
            .writer(&mut w)
            .begin_nd()?;
        npy.extend(data.iter().copied())?;
        npy.finish()
    })()
    .map_err(io_err(path))?;
    w.flush().map_err(io_err(path))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fortran_order_3d_becomes_row_major() {
        // shape (2, 3, 2): C offset of (i, j, k) = i*6 + j*2 + k; store value = C offset.
        let shape = [2usize, 3, 2];
        let mut fortran = Vec::new();
        for k in 0..2 {
            for j in 0..3 {
                for i in 0..2 {
                    fortran.push((i * 6 + j * 2 + k) as u16);
                }
            }
        }
        let c = fortran_to_c(&fortran, &shape);
        assert_eq!(c, (0..12).collect::<Vec<u16>>());
    }

    #[test]
    fn window_reads_only_the_asked_cells() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("f.npy");
        // 4 x 5 x 2, value = row*100 + col*10 + channel
        let mut data = Vec::new();
        for r in 0..4 {
            for c in 0..5 {
                for k in 0..2 {
                    data.push((r * 100 + c * 10 + k) as f32);
                }
            }
        }
        write_array(&p, &[4, 5, 2], &data).unwrap();
        let (shape, ch, win) = read_hwc_window_f32(&p, 1, 2, 2, 3).unwrap();
        assert_eq!((shape, ch), (vec![4, 5, 2], 2));
        assert_eq!(
            win,
            vec![120., 121., 130., 131., 140., 141., 220., 221., 230., 231., 240., 241.]
        );
        let (_, _, all) = read_hwc_window_f32(&p, 0, 4, 0, 5).unwrap();
        assert_eq!(all, data);
        let err = read_hwc_window_f32(&p, 3, 2, 0, 5).unwrap_err();
        assert!(err.to_string().contains("f.npy"), "{err}");
    }

    #[test]
    fn unsupported_dtype_names_it() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("c.npy");
        // complex64, which no map layer holds: a hand-written v1.0 header
        let mut header = "{'descr': '<c8', 'fortran_order': False, 'shape': (2,), }".to_string();
        while !(10 + header.len() + 1).is_multiple_of(64) {
            header.push(' ');
        }
        header.push('\n');
        let mut buf = b"\x93NUMPY\x01\x00".to_vec();
        buf.extend_from_slice(&u16::try_from(header.len()).unwrap().to_le_bytes());
        buf.extend_from_slice(header.as_bytes());
        buf.extend_from_slice(&[0u8; 16]);
        std::fs::write(&p, &buf).unwrap();
        let err = read_array(&p).unwrap_err().to_string();
        assert!(err.contains("c.npy") && err.contains("<c8"), "{err}");
    }
}
