//! The `.pvs` asset and its loader: the bytes read through Bevy's asset sources, checked
//! and opened by `sightline-runtime`, plus the index from source names to clusters that
//! the name mapping asks.

use bevy::asset::io::Reader;
use bevy::asset::{Asset, AssetLoader, LoadContext};
use bevy::reflect::TypePath;
use sightline_runtime::{Pvs, RuntimeError};
use std::collections::HashMap;
use std::sync::Arc;

/// An open `.pvs` (shared: cloning the asset clones two `Arc`s).
#[derive(Asset, TypePath, Clone, Debug)]
pub struct PvsAsset {
    pvs: Arc<Pvs>,
    /// A mesh level's source object name → its clusters, ascending.
    by_source_name: Arc<HashMap<String, Vec<u32>>>,
}

impl PvsAsset {
    /// Wrap an open file (as the loader does).
    pub fn new(pvs: Pvs) -> PvsAsset {
        let mut by_source_name: HashMap<String, Vec<u32>> = HashMap::new();
        if let (Some(sources), Some(names)) = (pvs.sources(), pvs.source_names()) {
            for (cluster, &source) in sources.iter().enumerate() {
                if let Some(name) = names.get(source as usize) {
                    by_source_name
                        .entry(name.clone())
                        .or_default()
                        .push(cluster as u32);
                }
            }
        }
        PvsAsset {
            pvs: Arc::new(pvs),
            by_source_name: Arc::new(by_source_name),
        }
    }

    /// The runtime's reader: locate, rows, neighbours, gameplay queries.
    pub fn pvs(&self) -> &Arc<Pvs> {
        &self.pvs
    }

    /// The clusters of a mesh level's source object `name` (empty when unknown or when the
    /// file has no source names).
    pub fn source_clusters(&self, name: &str) -> &[u32] {
        self.by_source_name.get(name).map_or(&[], Vec::as_slice)
    }
}

/// Reads `.pvs` files into [`PvsAsset`]s.
#[derive(Clone, Copy, Debug, Default, TypePath)]
pub struct PvsLoader;

/// Why a `.pvs` did not load.
#[derive(Debug, thiserror::Error)]
pub enum PvsLoadError {
    #[error("reading the .pvs: {0}")]
    Io(#[from] std::io::Error),
    #[error(transparent)]
    Pvs(#[from] RuntimeError),
}

impl AssetLoader for PvsLoader {
    type Asset = PvsAsset;
    type Settings = ();
    type Error = PvsLoadError;

    async fn load(
        &self,
        reader: &mut dyn Reader,
        _settings: &(),
        _load_context: &mut LoadContext<'_>,
    ) -> Result<PvsAsset, PvsLoadError> {
        let mut bytes = Vec::new();
        reader.read_to_end(&mut bytes).await?;
        Ok(PvsAsset::new(Pvs::from_vec(bytes)?))
    }

    fn extensions(&self) -> &[&str] {
        &["pvs"]
    }
}
