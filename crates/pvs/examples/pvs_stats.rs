//! Storage figures of a `.pvs` file: bytes per cell of the compressed sets, against a
//! plain sorted `u32` list per cell and a raw bitset per cell.
//! `cargo run --release -p sightline-pvs --example pvs_stats -- city.pvs`

use sightline_pvs::PvsFile;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let path = std::env::args().nth(1).ok_or("usage: pvs_stats FILE.pvs")?;
    let file = PvsFile::open(&path)?;
    let cells = file.cells().len();
    let objects = file.header().object_count as u64;
    let ids: u64 = (0..cells)
        .map(|c| file.set_len(c).unwrap_or(0) as u64)
        .sum();
    let (data, total) = file.sizes();
    let per_cell = data as f64 / cells.max(1) as f64;
    let list = ids as f64 * 4.0 / cells.max(1) as f64;
    let bitset = objects.div_ceil(8) as f64;
    println!(
        "{path}: {cells} cells, {objects} objects, mean PVS {:.1} ids; sets {per_cell:.1} B/cell \
         ({:.1} % of sorted u32 lists, {:.2} % of a bitset); file {total} B ({:.1} B/cell)",
        ids as f64 / cells.max(1) as f64,
        100.0 * per_cell / list.max(1e-9),
        100.0 * per_cell / bitset,
        total as f64 / cells.max(1) as f64,
    );
    Ok(())
}
