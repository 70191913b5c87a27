//! [`Registry`]: the registry as a value that can be extended with samplers defined elsewhere.

use crate::{
    BuiltDirection, DirectionRequest, RegistryError, SAMPLERS, SamplerEntry, closest_in,
    names_of_kind_in,
};

/// A set of sampler entries, by name: the built-in ones ([`Registry::builtin`]) plus any added
/// with [`Registry::with`]. The validation suite (`validation::run_with`) and the studies
/// (`study::StudyPlan::with_registry`) take one as a value, so a crate outside the workspace
/// (or the Python bindings) validates and studies its own sampler from its own `main`; the
/// command line passes the built-in one. Cloning is cheap (entries hold fn pointers or `Arc`s).
#[derive(Clone)]
pub struct Registry {
    entries: Vec<SamplerEntry>,
}

impl std::fmt::Debug for Registry {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_list()
            .entries(self.entries.iter().map(|e| e.name))
            .finish()
    }
}

impl Default for Registry {
    /// The built-in registry.
    fn default() -> Self {
        Self::builtin()
    }
}

impl Registry {
    /// Every sampler the project ships ([`SAMPLERS`]), in listing order.
    pub fn builtin() -> Self {
        Self {
            entries: SAMPLERS.to_vec(),
        }
    }

    /// A registry with no sampler.
    pub fn empty() -> Self {
        Self {
            entries: Vec::new(),
        }
    }

    /// This registry with `entry` added at the end, or in place of the entry of the same name
    /// (so a built-in sampler can be replaced by a variant of one's own).
    pub fn with(mut self, entry: SamplerEntry) -> Self {
        match self.entries.iter_mut().find(|e| e.name == entry.name) {
            Some(slot) => *slot = entry,
            None => self.entries.push(entry),
        }
        self
    }

    /// Every entry, in listing order.
    pub fn entries(&self) -> &[SamplerEntry] {
        &self.entries
    }

    /// Whether an entry is called `name`.
    pub fn contains(&self, name: &str) -> bool {
        self.entries.iter().any(|e| e.name == name.trim())
    }

    /// The entry called `name` (surrounding spaces ignored).
    ///
    /// Errors: [`RegistryError::UnknownSampler`] listing this registry's names, with the
    /// closest as a suggestion.
    pub fn find(&self, name: &str) -> Result<&SamplerEntry, RegistryError> {
        let name = name.trim();
        self.entries
            .iter()
            .find(|e| e.name == name)
            .ok_or_else(|| RegistryError::UnknownSampler {
                name: name.to_string(),
                suggestion: closest_in(&self.entries, name),
                known: self
                    .entries
                    .iter()
                    .map(|e| e.name)
                    .collect::<Vec<_>>()
                    .join(", "),
            })
    }

    /// The names of this registry's samplers of one kind, comma-separated.
    pub fn names_of_kind(&self, kind: &str) -> String {
        names_of_kind_in(&self.entries, kind)
    }

    /// Builds the direction sampler `name` (see [`SamplerEntry::build_direction`]).
    pub fn build_direction(
        &self,
        name: &str,
        request: &DirectionRequest<'_>,
    ) -> Result<BuiltDirection, RegistryError> {
        self.find(name)?.build_direction(request)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{Capabilities, Support};

    fn cosine_alias(name: &'static str) -> SamplerEntry {
        SamplerEntry::direction(
            name,
            "the cosine sampler under another name",
            Capabilities::default(),
            Support::Hemisphere,
            |r| Ok(crate::build_direction("cosine", r)?.sampler),
        )
    }

    #[test]
    fn with_adds_or_replaces_by_name() {
        let n = SAMPLERS.len();
        let r = Registry::builtin().with(cosine_alias("mine"));
        assert_eq!(r.entries().len(), n + 1);
        assert!(r.contains("mine") && r.find(" mine ").is_ok());
        let r = r.with(cosine_alias("cosine"));
        assert_eq!(r.entries().len(), n + 1);
        assert_eq!(
            r.find("cosine").unwrap().summary,
            "the cosine sampler under another name"
        );
        assert!(r.names_of_kind("direction").contains("mine"));
    }

    #[test]
    fn unknown_names_suggest_from_this_registry() {
        let r = Registry::empty().with(cosine_alias("my-lobe"));
        let err = r.find("my-lob").unwrap_err().to_string();
        assert!(err.contains("did you mean `my-lobe`"), "{err}");
        assert!(err.contains("known samplers: my-lobe"), "{err}");
    }

    #[test]
    fn user_build_errors_are_typed() {
        let e = SamplerEntry::direction(
            "fails",
            "always fails",
            Capabilities::default(),
            Support::Hemisphere,
            |_| Err("no table for this BRDF".into()),
        );
        let brdf: std::sync::Arc<dyn brdf::Brdf> =
            std::sync::Arc::from(brdf::parse_spec("lambert").unwrap());
        let options = brdf_sampling::SetOptions::default();
        let err = Registry::builtin()
            .with(e)
            .build_direction("fails", &DirectionRequest::new(brdf, &options))
            .unwrap_err();
        assert!(matches!(err, RegistryError::User { name: "fails", .. }));
        assert_eq!(err.to_string(), "sampler `fails`: no table for this BRDF");
    }
}
