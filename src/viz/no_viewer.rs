//! Without the cargo feature `rerun`: nothing can be recorded.

use super::{Entity, Target};
use crate::error::Error;

/// Uninhabited: a recorder never has one in this build.
pub enum Inner {}

impl Inner {
    pub fn start(tool: &'static str, target: &Target) -> crate::Result<Option<Inner>> {
        if let Some(path) = &target.save {
            return Err(Error::Invalid(format!(
                "--rerun-save {path}: this build of pgo has no rerun support (it was built without the cargo feature `rerun`, which is on by default)"
            )));
        }
        eprintln!(
            "{tool}: warning: {} ignored: this build of pgo has no rerun support (cargo feature `rerun`)",
            if target.spawn {
                "--rerun-spawn"
            } else {
                "--rerun-connect"
            }
        );
        Ok(None)
    }

    pub fn emit(&self, _entity: &Entity) {
        match *self {}
    }

    pub fn observer(
        &self,
        _next_step: std::rc::Rc<std::cell::Cell<u64>>,
    ) -> crate::progress::Observer {
        match *self {}
    }

    pub fn finish(self) -> crate::Result<()> {
        match self {}
    }
}
