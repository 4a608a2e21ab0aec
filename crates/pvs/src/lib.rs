//! PVS store of sightline: batch build with a checkpoint journal, the `.pvs` file
//! format (SPEC §6), point queries, shards and merge.
