//! swarf's errors as Python exceptions. Each carries what the library's [`swarf::Error`]
//! carries, as attributes:
//!
//! ```text
//! SwarfError (Exception)
//! ├── InputError                      file, place, reason   a bad input file
//! ├── SettingError                    setting, reason       an option out of its range
//! ├── JobError                        place, reason         a job that cannot be machined as asked
//! ├── RefusedError                    file, reason          an output refused before anything is written
//! └── OutputError                     what, reason          an output that cannot be made
//! ```
//!
//! Reading or writing a file that fails is Python's own `OSError` with the path as its filename.

use pyo3::create_exception;
use pyo3::exceptions::{PyException, PyOSError};
use pyo3::prelude::*;
use swarf::Error;

create_exception!(_swarf, SwarfError, PyException, "Every error swarf raises about what it was given.");
create_exception!(_swarf, InputError, SwarfError, "A bad input file: `file`, `place` (where in it) and `reason`.");
create_exception!(
    _swarf,
    SettingError,
    SwarfError,
    "An option out of its range: `setting` (its name in the library) and `reason`."
);
create_exception!(
    _swarf,
    JobError,
    SwarfError,
    "A job that cannot be machined as asked: `place` (the aspect of the job) and `reason`."
);
create_exception!(
    _swarf,
    RefusedError,
    SwarfError,
    "An output refused before anything is written: `file` and `reason`."
);
create_exception!(_swarf, OutputError, SwarfError, "An output that cannot be made: `what` and `reason`.");

/// The exception of `e`, with its attributes.
pub fn to_py(py: Python<'_>, e: Error) -> PyErr {
    let msg = e.to_string();
    let (err, attrs): (PyErr, Vec<(&str, String)>) = match e {
        Error::Input { file, place, reason } => {
            (InputError::new_err(msg), vec![("file", file.display().to_string()), ("place", place), ("reason", reason)])
        }
        Error::Import(i) => (
            InputError::new_err(msg),
            vec![("file", i.file.display().to_string()), ("place", i.place), ("reason", i.reason)],
        ),
        Error::Setting { setting, reason } => {
            (SettingError::new_err(msg), vec![("setting", setting.name().to_string()), ("reason", reason)])
        }
        Error::Job { place, reason } => (JobError::new_err(msg), vec![("place", place), ("reason", reason)]),
        Error::Refused { file, reason } => {
            (RefusedError::new_err(msg), vec![("file", file.display().to_string()), ("reason", reason)])
        }
        Error::Output { what, reason } => (OutputError::new_err(msg), vec![("what", what), ("reason", reason)]),
        Error::Io { path, source } => {
            return PyOSError::new_err((
                source.raw_os_error().unwrap_or(0),
                source.to_string(),
                path.display().to_string(),
            ));
        }
    };
    let value = err.value(py);
    for (k, v) in attrs {
        // (setting an attribute on a fresh exception instance does not fail)
        let _ = value.setattr(k, v);
    }
    err
}

/// Adds the exceptions to the module.
pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    let py = m.py();
    m.add("SwarfError", py.get_type::<SwarfError>())?;
    m.add("InputError", py.get_type::<InputError>())?;
    m.add("SettingError", py.get_type::<SettingError>())?;
    m.add("JobError", py.get_type::<JobError>())?;
    m.add("RefusedError", py.get_type::<RefusedError>())?;
    m.add("OutputError", py.get_type::<OutputError>())?;
    Ok(())
}
