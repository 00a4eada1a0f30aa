//! A bake split into shards (docs/CLUSTER.md): every method's bake makes its long work's rows
//! through [`WorkOptions::gather`](crate::work::WorkOptions::gather), one row of fixed width per
//! work item (a texel, a vertex), each row a function of its item and the seed alone. A plan
//! runs the bake up to its gather, records the items and their sampled costs and stops; a
//! shard runs it again and makes the rows of its range of items into a part; the merge runs it
//! once more, reading every row from the parts instead of making it, and reduces. The rows are
//! the same bytes whoever made them, so the merged artifact is the one-process bake's.

use crate::artifact::{checksum, file_checksum};
use crate::outputs::Outputs;
use bytemuck::Pod;
use serde_json::{json, Value};
use std::fs::File;
use std::io::{BufReader, BufWriter, Read, Write};
use std::ops::Range;
use std::path::{Path, PathBuf};
use std::sync::Mutex;
use std::time::Instant;

/// What one gather of a bake makes: `count` items of `width` values each (f32, f64 or a Vec3
/// of f32, as the bake keeps them), made and taken in the pieces `chunks` ends (ascending, the last `count`):
/// a light cloud's zones, FIV's tables, or one piece. A bake may gather more than once (the
/// light path maps: their obscurance, then their transfers): a gather `followed` by another
/// is one whose rows nothing reads before that next gather.
#[derive(Clone, Debug, PartialEq)]
pub struct Items {
    pub count: u64,
    pub width: usize,
    /// Bytes a value takes (4, 8 or 12).
    pub value_bytes: usize,
    pub chunks: Vec<u64>,
    pub followed: bool,
}

impl Items {
    /// Items in one piece, of `width` values of `T`.
    pub fn whole<T>(count: u64, width: usize) -> Items {
        Items::chunked::<T>(width, vec![count])
    }

    /// Items in the pieces `chunks` ends, of `width` values of `T`.
    pub fn chunked<T>(width: usize, chunks: Vec<u64>) -> Items {
        Items { count: chunks.last().copied().unwrap_or(0), width, value_bytes: std::mem::size_of::<T>(), chunks, followed: false }
    }

    /// Items in pieces of `sizes` items each, of `width` values of `T`.
    pub fn sized<T>(width: usize, sizes: impl IntoIterator<Item = u64>) -> Items {
        let ends = sizes
            .into_iter()
            .scan(0, |end, size| {
                *end += size;
                Some(*end)
            })
            .collect();
        Items::chunked::<T>(width, ends)
    }

    /// The same items, followed by another gather (`followed` true) or not.
    pub fn followed(self, followed: bool) -> Items {
        Items { followed, ..self }
    }

    /// Bytes of the rows of `items` items.
    fn bytes(&self, items: u64) -> u64 {
        items * (self.width * self.value_bytes) as u64
    }

    /// The parts of `range` each within one chunk, in order, with their chunk's index.
    fn pieces(&self, range: Range<u64>) -> Vec<(usize, Range<u64>)> {
        let within = |(chunk, whole): (usize, Range<u64>)| {
            let piece = whole.start.max(range.start)..whole.end.min(range.end);
            (piece.start < piece.end).then_some((chunk, piece))
        };
        self.chunk_ranges().into_iter().enumerate().filter_map(within).collect()
    }

    /// Every chunk's range, empty ones too.
    fn chunk_ranges(&self) -> Vec<Range<u64>> {
        let starts = std::iter::once(0).chain(self.chunks.iter().copied());
        starts.zip(&self.chunks).map(|(start, &end)| start..end).collect()
    }

    /// Whether the items could be a bake's: chunks ascending to `count`, values of a size a
    /// gather takes, and rows whose bytes a part's size can hold.
    fn consistent(&self) -> bool {
        let ascending = self.chunks.windows(2).all(|w| w[0] <= w[1]) && self.chunks.last() == Some(&self.count);
        let bytes = self.count.checked_mul(self.width as u64).and_then(|v| v.checked_mul(self.value_bytes as u64));
        ascending && [4, 8, 12].contains(&self.value_bytes) && bytes.is_some_and(|b| b < 1 << 60)
    }

    fn json(&self) -> Value {
        json!({ "count": self.count, "width": self.width, "value_bytes": self.value_bytes, "chunks": self.chunks, "followed": self.followed })
    }

    fn from_json(items: &Value) -> Option<Items> {
        let number = |key: &str| items[key].as_u64();
        let chunks = items["chunks"].as_array()?.iter().map(Value::as_u64).collect::<Option<Vec<u64>>>()?;
        Some(Items {
            count: number("count")?,
            width: number("width")? as usize,
            value_bytes: number("value_bytes")? as usize,
            chunks,
            followed: items["followed"].as_bool()?,
        })
    }
}

/// The part of the bake's items `range` (numbered over every gather in turn) that falls in a
/// gather of `count` items starting at `offset`, numbered within the gather.
fn within(range: &Range<u64>, offset: u64, count: u64) -> Range<u64> {
    let start = range.start.clamp(offset, offset + count);
    start - offset..range.end.clamp(start, offset + count) - offset
}

/// The error a plan's or a shard's bake ends with once its last gather is done: the caller
/// takes it as success (`stopped`).
pub const STOPPED: &str = "the bake stopped after its gather, as a plan or a shard does";

/// Whether a bake's error is the stop a plan or a shard asks for.
pub fn stopped(error: &str) -> bool {
    error.contains(STOPPED)
}

/// What the gathers do in a bake that is part of a sharded one.
pub enum Role {
    /// Records each gather's items and their costs, sampled on `strata` stretches of each.
    Plan { strata: u64, found: Mutex<Planned> },
    /// Makes the rows of the items `range` into the part `index` in `folder`.
    Shard { range: Range<u64>, folder: PathBuf, index: usize, made: Mutex<Vec<Made>> },
    /// Reads every row from the parts instead of making it, `rows[gather][part]`, checking
    /// each gather's items against the plan's `gathers`; `read`: the gathers read so far.
    Merge { gathers: Vec<Items>, rows: Vec<Vec<PathBuf>>, read: Mutex<usize> },
}

impl Role {
    /// What a plan's gathers found (nothing for another role).
    pub fn planned(&self) -> Planned {
        match self {
            Role::Plan { found, .. } => std::mem::take(&mut *locked(found)),
            _ => Planned::default(),
        }
    }

    /// What a shard's gathers wrote (nothing for another role).
    pub fn made(&self) -> Vec<Made> {
        match self {
            Role::Shard { made, .. } => std::mem::take(&mut *locked(made)),
            _ => Vec::new(),
        }
    }
}

impl std::fmt::Debug for Role {
    fn fmt(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
        f.write_str(match self {
            Role::Plan { .. } => "plan",
            Role::Shard { .. } => "shard",
            Role::Merge { .. } => "merge",
        })
    }
}

/// The one role a process has: compared by identity.
impl PartialEq for Role {
    fn eq(&self, other: &Role) -> bool {
        std::ptr::eq(self, other)
    }
}

/// What a plan's gathers found.
#[derive(Clone, Debug, Default)]
pub struct Planned {
    pub gathers: Vec<Items>,
    /// Seconds per item of each stratum, sampled, numbered over every gather in turn.
    pub costs: Vec<(Range<u64>, f64)>,
}

impl Planned {
    /// Items over every gather.
    pub fn count(&self) -> u64 {
        self.gathers.iter().map(|g| g.count).sum()
    }
}

/// What one gather of a shard wrote.
#[derive(Clone, Debug)]
pub struct Made {
    pub items: Items,
    pub bytes: u64,
    pub checksum: String,
}

/// Items a plan times in each stratum: one in this many (at least one).
const SAMPLED_SHARE: u64 = 128;

fn locked<T>(mutex: &Mutex<T>) -> std::sync::MutexGuard<'_, T> {
    mutex.lock().unwrap_or_else(|e| e.into_inner())
}

/// Runs a gather in `role` (None: the whole bake): `make(chunk, range)` makes the rows of a
/// range of items within the chunk `chunk`, `take` takes every chunk's rows in order.
pub fn gather<T: Pod>(
    role: Option<&Role>,
    items: &Items,
    mut make: impl FnMut(usize, Range<u64>) -> Result<Vec<T>, String> + Send,
    mut take: impl FnMut(Vec<T>) -> Result<(), String>,
) -> Result<(), String> {
    if items.value_bytes != std::mem::size_of::<T>() {
        return Err(format!("the gather's items hold {}-byte values, its rows {}-byte ones", items.value_bytes, std::mem::size_of::<T>()));
    }
    let mut checked = |(chunk, range): (usize, Range<u64>)| {
        let rows = make(chunk, range.clone())?;
        match rows.len() as u64 == (range.end - range.start) * items.width as u64 {
            true => Ok(rows),
            false => Err(format!("the gather made {} values for items {range:?} of width {}", rows.len(), items.width)),
        }
    };
    match role {
        None => items.chunk_ranges().into_iter().enumerate().try_for_each(|chunk| take(checked(chunk)?)),
        Some(Role::Plan { strata, found }) => {
            let offset = locked(found).count();
            let costs = sample(items, *strata, checked)?;
            let mut found = locked(found);
            found.costs.extend(costs.into_iter().map(|(r, c)| (r.start + offset..r.end + offset, c)));
            found.gathers.push(items.clone());
            drop(found);
            go_on(items)
        }
        Some(Role::Shard { range, folder, index, made }) => {
            let gather = locked(made).len();
            let offset: u64 = locked(made).iter().map(|m| m.items.count).sum();
            let path = part_rows(folder, *index, gather);
            let (bytes, checksum) = write_rows(&path, items, within(range, offset, items.count), checked)?;
            locked(made).push(Made { items: items.clone(), bytes, checksum });
            go_on(items)
        }
        Some(Role::Merge { gathers, rows, read }) => {
            let gather = {
                let mut read = locked(read);
                *read += 1;
                *read - 1
            };
            if gathers.get(gather) != Some(items) {
                return Err(format!("the bake's gather {gather} is not the plan's ({items:?}): the plan is not this bake's; plan again"));
            }
            let parts = &rows[gather];
            let mut reader = PartsReader { parts: parts.iter(), current: None };
            items.chunk_ranges().into_iter().try_for_each(|chunk| take(reader.read((chunk.end - chunk.start) as usize * items.width)?))?;
            reader.finish()
        }
    }
}

/// After a plan's or a shard's gather: on to the next gather without its rows (nothing reads
/// them before it), or the stop after the last.
fn go_on(items: &Items) -> Result<(), String> {
    match items.followed {
        true => Ok(()),
        false => Err(STOPPED.into()),
    }
}

/// The rows file of gather `gather` of part `index` in the parts' `folder`.
pub fn part_rows(folder: &Path, index: usize, gather: usize) -> PathBuf {
    folder.join(format!("part-{index}-{gather}.rows"))
}

/// The seconds per item of at most `strata` equal stretches of the items, each timed on its
/// first items (one in [`SAMPLED_SHARE`]) on one thread (the bake's work options give the
/// plan's gathers no pool of their own): an item's cost whatever threads a shard has.
fn sample<T>(
    items: &Items,
    strata: u64,
    mut make: impl FnMut((usize, Range<u64>)) -> Result<Vec<T>, String> + Send,
) -> Result<Vec<(Range<u64>, f64)>, String> {
    // Few enough stretches that one item in SAMPLED_SHARE is timed, however few the items.
    let strata = strata.min(items.count.div_ceil(SAMPLED_SHARE)).max(1);
    crate::work::with_threads(Some(1), || {
        let mut costs = Vec::new();
        for s in 0..strata {
            let stratum = items.count * s / strata..items.count * (s + 1) / strata;
            let taken = ((stratum.end - stratum.start) / SAMPLED_SHARE).max(1).min(stratum.end - stratum.start);
            let start = Instant::now();
            for piece in items.pieces(stratum.start..stratum.start + taken) {
                make(piece)?;
            }
            costs.push((stratum, start.elapsed().as_secs_f64() / taken.max(1) as f64));
        }
        Ok(costs)
    })
}

/// Writes the rows of `range` into `path` (staged, moved in place whole); returns its size
/// and checksum.
fn write_rows<T: Pod>(
    path: &Path,
    items: &Items,
    range: Range<u64>,
    mut make: impl FnMut((usize, Range<u64>)) -> Result<Vec<T>, String>,
) -> Result<(u64, String), String> {
    let mut outputs = Outputs::new();
    outputs
        .file(path, |file| {
            let mut writer = BufWriter::new(file);
            for piece in items.pieces(range) {
                let rows = make(piece)?;
                writer.write_all(bytemuck::cast_slice(&rows)).map_err(|e| e.to_string())?;
            }
            writer.flush().map_err(|e| e.to_string())
        })
        .map_err(|e| e.to_string())?;
    outputs.commit().map_err(|e| e.to_string())?;
    let bytes = std::fs::metadata(path).map_err(|e| format!("{}: {e}", path.display()))?.len();
    Ok((bytes, file_checksum(path).map_err(|e| format!("{}: {e}", path.display()))?))
}

/// The parts' rows read in order, as one stream.
struct PartsReader<'p> {
    parts: std::slice::Iter<'p, PathBuf>,
    current: Option<(PathBuf, BufReader<File>)>,
}

impl PartsReader<'_> {
    fn read<T: Pod>(&mut self, values: usize) -> Result<Vec<T>, String> {
        let mut rows = vec![T::zeroed(); values];
        let mut bytes: &mut [u8] = bytemuck::cast_slice_mut(&mut rows);
        while !bytes.is_empty() {
            let Some((path, reader)) = &mut self.current else {
                let path = self.parts.next().ok_or("the parts hold fewer rows than the bake's items: the plan is not this bake's")?;
                let file = File::open(path).map_err(|e| format!("{}: {e}", path.display()))?;
                self.current = Some((path.clone(), BufReader::with_capacity(1 << 20, file)));
                continue;
            };
            match reader.read(bytes).map_err(|e| format!("{}: {e}", path.display()))? {
                0 => self.current = None,
                n => bytes = &mut bytes[n..],
            }
        }
        Ok(rows)
    }

    /// Refuses rows left over once every item is read (a part whose range lies past this
    /// gather holds none of its rows).
    fn finish(self) -> Result<(), String> {
        let opened =
            |path: &PathBuf| File::open(path).map(|f| (path.clone(), BufReader::new(f))).map_err(|e| format!("{}: {e}", path.display()));
        let rest = self.parts.map(opened).collect::<Result<Vec<_>, _>>()?;
        for (path, mut reader) in self.current.into_iter().chain(rest) {
            if reader.read(&mut [0u8]).map_err(|e| format!("{}: {e}", path.display()))? > 0 {
                return Err(format!("{}: holds more rows than its range: the plan is not this bake's", path.display()));
            }
        }
        Ok(())
    }
}

/// `shards` ranges over the items, each of about the same sampled cost; refused with more
/// shards than items.
pub fn balanced(planned: &Planned, shards: u64) -> Result<Vec<Range<u64>>, String> {
    let count = planned.count();
    if shards == 0 || shards > count {
        return Err(format!("{shards} shards of {count} work items: give 1 to {count} shards"));
    }
    // A stratum that timed at zero still counts: every item costs something.
    let floor = planned.costs.iter().map(|c| c.1).fold(0.0, f64::max).max(1e-12) * 1e-3;
    let cost = |r: &Range<u64>, c: f64| (r.end - r.start) as f64 * c.max(floor);
    let total: f64 = planned.costs.iter().map(|(r, c)| cost(r, *c)).sum();
    let mut ends = Vec::new();
    let mut before = 0.0;
    for (stratum, c) in &planned.costs {
        let here = cost(stratum, *c);
        while (ends.len() as u64) < shards - 1 {
            let goal = total * (ends.len() + 1) as f64 / shards as f64;
            if goal > before + here {
                break;
            }
            let into = ((goal - before) / c.max(floor)).round() as u64;
            ends.push((stratum.start + into).min(stratum.end));
        }
        before += here;
    }
    ends.push(count);
    // Every shard keeps at least one item.
    let mut ranges = Vec::new();
    let mut start = 0;
    for (k, &end) in ends.iter().enumerate() {
        let end = end.max(start + 1).min(count - (shards - 1 - k as u64));
        ranges.push(start..end);
        start = end;
    }
    Ok(ranges)
}

/// The plan file's name in a plan folder.
pub const PLAN_FILE: &str = "plan.json";

/// A plan as its file holds it.
#[derive(Clone, Debug)]
pub struct Plan {
    pub folder: PathBuf,
    pub json: Value,
    /// The checksum of the plan file's bytes: what each part names.
    pub checksum: String,
    pub ranges: Vec<Range<u64>>,
    pub gathers: Vec<Items>,
}

/// Which build of relume made a plan or part: its version and its program's checksum.
pub fn build() -> Result<Value, String> {
    let program = std::env::current_exe().map_err(|e| format!("cannot find relume's own program: {e}"))?;
    let sum = file_checksum(&program).map_err(|e| format!("{}: {e}", program.display()))?;
    Ok(json!({ "version": env!("CARGO_PKG_VERSION"), "program": sum }))
}

impl Plan {
    /// The plan file's contents for `planned` split into `ranges`, with `facts` (the bake's
    /// arguments, scene, settings) beside them.
    pub fn contents(facts: Value, planned: &Planned, ranges: &[Range<u64>]) -> Result<Value, String> {
        let costs: Vec<Value> = planned.costs.iter().map(|(r, c)| json!({ "items": [r.start, r.end], "seconds_per_item": c })).collect();
        let seconds: f64 = planned.costs.iter().map(|(r, c)| (r.end - r.start) as f64 * c).sum();
        Ok(json!({
            "format": "relume bake plan",
            "build": build()?,
            "bake": facts,
            "gathers": planned.gathers.iter().map(Items::json).collect::<Vec<_>>(),
            "sampled_costs": costs,
            "estimated_seconds": seconds,
            "shards": ranges.iter().map(|r| json!([r.start, r.end])).collect::<Vec<_>>(),
        }))
    }

    /// Reads the plan in `folder`, refusing one made by another build of relume or whose
    /// shards do not cover its items once, in order.
    pub fn read(folder: &Path) -> Result<Plan, String> {
        let path = folder.join(PLAN_FILE);
        let bytes = std::fs::read(&path).map_err(|e| format!("{}: {e} (make the plan with `relume bake plan`)", path.display()))?;
        let again = |what: &str| format!("{}: {what}: make the plan again with `relume bake plan`", path.display());
        let json: Value = serde_json::from_slice(&bytes).map_err(|e| again(&format!("not a plan ({e})")))?;
        if json["format"] != "relume bake plan" {
            return Err(again("not a relume bake plan"));
        }
        let build = build()?;
        if json["build"] != build {
            return Err(format!(
                "{}: made by relume {} (program {}), not by this one ({}, program {}): run every shard and the merge with the program that made the plan, or plan again",
                path.display(),
                json["build"]["version"],
                json["build"]["program"],
                build["version"],
                build["program"]
            ));
        }
        let ranges = json["shards"]
            .as_array()
            .and_then(|shards| shards.iter().map(|r| Some(r[0].as_u64()?..r[1].as_u64()?)).collect::<Option<Vec<_>>>())
            .ok_or_else(|| again("its shards are not ranges of items"))?;
        let gathers = json["gathers"]
            .as_array()
            .and_then(|g| g.iter().map(Items::from_json).collect::<Option<Vec<_>>>())
            .ok_or_else(|| again("its gathers do not read"))?;
        if let Some(g) = gathers.iter().find(|g| !g.consistent()) {
            return Err(again(&format!("a gather's items do not hold together ({g:?})")));
        }
        let plan = Plan { folder: folder.to_path_buf(), json, checksum: checksum(&bytes), ranges, gathers };
        plan.check_cover().map_err(|e| again(&e))?;
        Ok(plan)
    }

    fn check_cover(&self) -> Result<(), String> {
        let count = self.gathers.iter().try_fold(0u64, |sum, g| sum.checked_add(g.count)).ok_or("its gathers hold too many items")?;
        let mut next = 0;
        for (i, r) in self.ranges.iter().enumerate() {
            if r.start != next || r.end <= r.start {
                return Err(format!("shard {i}'s items {r:?} do not follow on from {next}"));
            }
            next = r.end;
        }
        match (next == count, self.ranges.is_empty()) {
            (true, false) => Ok(()),
            _ => Err(format!("its shards cover {next} of {count} items")),
        }
    }

    /// The range of shard `index`, or a refusal naming the plan's shards.
    pub fn range(&self, index: usize) -> Result<Range<u64>, String> {
        self.ranges
            .get(index)
            .cloned()
            .ok_or_else(|| format!("--index {index}: the plan {} has shards 0 to {}", self.folder.display(), self.ranges.len() - 1))
    }

    /// The folder of the shards' parts.
    pub fn parts(&self) -> PathBuf {
        self.folder.join("parts")
    }

    /// Shard `index`'s manifest.
    pub fn part_manifest_path(&self, index: usize) -> PathBuf {
        self.parts().join(format!("part-{index}.json"))
    }

    /// Each gather's part of shard `index`'s items, numbered within the gather.
    fn local_ranges(&self, index: usize) -> Vec<Range<u64>> {
        let mut offset = 0;
        self.gathers
            .iter()
            .map(|g| {
                offset += g.count;
                within(&self.ranges[index], offset - g.count, g.count)
            })
            .collect()
    }

    /// The manifest of shard `index`'s part, once its rows are written; refused when the bake
    /// gathered other items than the plan's.
    pub fn part_manifest(&self, index: usize, made: &[Made]) -> Result<Value, String> {
        let items: Vec<Items> = made.iter().map(|m| m.items.clone()).collect();
        if items != self.gathers {
            return Err(format!(
                "the bake's work items are not the plan's {} ({items:?} against {:?}): plan again",
                self.folder.display(),
                self.gathers
            ));
        }
        let range = &self.ranges[index];
        let gathers: Vec<Value> = made.iter().map(|m| json!({ "bytes": m.bytes, "checksum": m.checksum })).collect();
        Ok(json!({ "plan": self.checksum, "index": index, "items": [range.start, range.end], "gathers": gathers }))
    }

    /// Checks shard `index`'s part against this plan: its manifest names this plan and its
    /// range, and each gather's rows have the size and (`whole`: reading every byte) the
    /// checksum the manifest records; refusals name the part and the fix.
    pub fn check_part(&self, index: usize, whole: bool) -> Result<(), String> {
        let manifest = self.part_manifest_path(index);
        let rerun = format!("run `relume bake shard {} --index {index}` again", self.folder.display());
        let bytes = std::fs::read(&manifest).map_err(|e| format!("{}: part {index} is missing ({e}): {rerun}", manifest.display()))?;
        let part: Value = serde_json::from_slice(&bytes)
            .map_err(|e| format!("{}: not a part's manifest ({e}): remove it and {rerun}", manifest.display()))?;
        if part["plan"] != self.checksum.as_str() {
            return Err(format!(
                "{}: part {index} belongs to another plan ({}; this plan is {}): remove it and {rerun}",
                manifest.display(),
                part["plan"],
                self.checksum
            ));
        }
        let range = &self.ranges[index];
        let sizes: Vec<u64> = self.local_ranges(index).iter().zip(&self.gathers).map(|(r, g)| g.bytes(r.end - r.start)).collect();
        let recorded: Vec<Value> = sizes.iter().map(|&b| json!(b)).collect();
        let listed: Vec<Value> = part["gathers"].as_array().into_iter().flatten().map(|g| g["bytes"].clone()).collect();
        if part["index"] != index || part["items"] != json!([range.start, range.end]) || listed != recorded {
            return Err(format!("{}: part {index}'s range or sizes are not the plan's: remove it and {rerun}", manifest.display()));
        }
        for (gather, &expected) in sizes.iter().enumerate() {
            let rows = part_rows(&self.parts(), index, gather);
            let size =
                std::fs::metadata(&rows).map_err(|e| format!("{}: part {index}'s rows are missing ({e}): {rerun}", rows.display()))?.len();
            let wanted = &part["gathers"][gather]["checksum"];
            let sum = match whole {
                true => file_checksum(&rows).map_err(|e| format!("{}: {e}", rows.display()))?,
                false => wanted.as_str().unwrap_or_default().to_string(),
            };
            if size != expected || wanted != sum.as_str() {
                return Err(format!(
                    "{}: part {index}'s rows do not match its manifest ({size} bytes, checksum {sum}; the manifest says {expected} bytes, {wanted}): the part is damaged; remove it and {rerun}",
                    rows.display()
                ));
            }
        }
        Ok(())
    }

    /// The shards whose parts are missing or do not check (`whole`: their every byte), each
    /// with why.
    pub fn unfinished(&self, whole: bool) -> Vec<(usize, String)> {
        (0..self.ranges.len()).filter_map(|i| self.check_part(i, whole).err().map(|e| (i, e))).collect()
    }

    /// What the merge reads: every gather's rows files, part by part.
    pub fn merge_role(&self) -> Role {
        let rows = (0..self.gathers.len()).map(|g| (0..self.ranges.len()).map(|i| part_rows(&self.parts(), i, g)).collect()).collect();
        Role::Merge { gathers: self.gathers.clone(), rows, read: Mutex::new(0) }
    }

    /// What shard `index` does.
    pub fn shard_role(&self, index: usize) -> Role {
        Role::Shard { range: self.ranges[index].clone(), folder: self.parts(), index, made: Mutex::new(Vec::new()) }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pieces_keep_within_chunks_and_cover_the_range() {
        let items = Items::chunked::<f32>(1, vec![3, 3, 7, 10]);
        assert_eq!(items.pieces(0..10), [(0, 0..3), (2, 3..7), (3, 7..10)]);
        assert_eq!(items.pieces(2..8), [(0, 2..3), (2, 3..7), (3, 7..8)]);
        assert_eq!(items.pieces(4..5), [(2, 4..5)]);
    }

    /// Balanced ranges cover every item once, each shard at least one, and give a shard of
    /// cheap items more of them than a shard of dear ones.
    #[test]
    fn balanced_ranges_cover_every_item_and_follow_the_costs() {
        let items = Items::whole::<f32>(100, 3);
        let planned = Planned { gathers: vec![items], costs: vec![(0..50, 1.0), (50..100, 3.0)] };
        let ranges = balanced(&planned, 4).unwrap();
        assert_eq!(ranges.first().unwrap().start, 0);
        assert_eq!(ranges.last().unwrap().end, 100);
        assert!(ranges.windows(2).all(|w| w[0].end == w[1].start && w[0].end > w[0].start), "{ranges:?}");
        assert!(ranges[0].end - ranges[0].start > ranges[3].end - ranges[3].start, "{ranges:?}");
        assert_eq!(ranges[1].end, 67, "half the cost lies before item 50 + 50/3: {ranges:?}");
        let few = Planned { gathers: vec![Items::whole::<f32>(7, 1)], costs: vec![(0..7, 0.0)] };
        assert_eq!(balanced(&few, 7).unwrap(), (0..7).map(|i| i..i + 1).collect::<Vec<_>>());
        assert!(balanced(&few, 8).unwrap_err().contains("8 shards of 7 work items"));
    }
}
