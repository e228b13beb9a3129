//! The prompt cache on disk: KV-cache snapshots of long prompt prefixes, so that a new
//! process does not evaluate again a prefix an earlier one already did (the worked
//! examples of `--all-examples` are thousands of tokens: about a minute of prompt
//! processing on 2 CPU threads, a fraction of a second to read back).
//!
//! Layout: `<dir>/<model key>/<n>.kv` (llama.cpp's `llama_state_seq_save_file`: the
//! sequence's keys and values, with its tokens) beside `<n>.tokens` (the same tokens as
//! little-endian `i32`, read at start-up to choose an entry without loading it). The model
//! key is the GGUF's file name, size and modification time, so a changed model never reads
//! another's snapshot, followed by the evaluation's settings (threads, batch size, and
//! flash attention when it is set, whose values llama.cpp lays out otherwise;
//! `snapshot_settings` in `llama.rs`): llama.cpp's sums run in another order with another
//! thread count, and measured (Qwen 1.5B, a people.nav instruction) a prefix evaluated on 1
//! thread and read back by a 2-thread run changed a greedy answer (`#{colour: "black"}`
//! where 2 threads from scratch write `#{ordinal: 1, colour: "black"}`), so a snapshot is
//! read back only under the settings that wrote it. An entry counts only when both files
//! are there; a snapshot llama.cpp refuses to load (another llama.cpp version, a truncated
//! file) is deleted.
//!
//! What is saved: when a request reuses at least [`MIN_TOKENS`] tokens of a slot (the
//! prefix two requests shared) and no entry already covers that prefix, the slot's
//! sequence holds exactly that prefix at that moment, and it is written. Also when a
//! request shares at least [`MIN_TOKENS`] more tokens with one of the last
//! [`RECENT_PROMPTS`] prompts ([`DiskCache::asked_before`]) than its slot still held (the
//! slots' cells went to other prefixes in between, as two long prefixes taking turns in a
//! small KV cache do): the slot then holds the whole prompt just evaluated, and that is
//! written. At most [`MAX_ENTRIES`] entries per model are kept, the oldest removed first.

use std::fs;
use std::path::{Path, PathBuf};
use std::time::UNIX_EPOCH;

use llama_cpp_2::token::LlamaToken;

/// Shorter shared prefixes are not worth a file (they take seconds to evaluate).
pub const MIN_TOKENS: usize = 512;

/// Entries kept per model.
pub const MAX_ENTRIES: usize = 8;

/// Prompts remembered by [`DiskCache::asked_before`].
pub const RECENT_PROMPTS: usize = 8;

/// One saved prefix.
#[derive(Debug, Clone)]
pub struct Entry {
    /// The `.kv` snapshot.
    pub kv: PathBuf,
    /// Its tokens, in position order.
    pub tokens: Vec<LlamaToken>,
}

impl Entry {
    fn sidecar(&self) -> PathBuf {
        self.kv.with_extension("tokens")
    }
}

/// The entries of one model's folder.
#[derive(Debug)]
pub struct DiskCache {
    dir: PathBuf,
    entries: Vec<Entry>,
    /// The last [`RECENT_PROMPTS`] prompts of this process, newest last.
    recent: Vec<Vec<LlamaToken>>,
}

/// The folder name for a model evaluated under `settings`: its file name, size and
/// modification time, then the settings.
fn model_key(model: &Path, settings: &str) -> Option<String> {
    let meta = fs::metadata(model).ok()?;
    let mtime = meta
        .modified()
        .ok()
        .and_then(|t| t.duration_since(UNIX_EPOCH).ok())
        .map_or(0, |d| d.as_secs());
    let name = folder_safe(&model.file_name()?.to_string_lossy());
    let settings = folder_safe(settings);
    Some(format!("{name}-{}-{mtime}-{settings}", meta.len()))
}

/// `s` with every character but ASCII letters, digits, `.`, `-` and `_` made `_`.
fn folder_safe(s: &str) -> String {
    s.chars()
        .map(|c| {
            if c.is_ascii_alphanumeric() || matches!(c, '.' | '-' | '_') {
                c
            } else {
                '_'
            }
        })
        .collect()
}

/// Length of the common prefix of two token lists.
#[must_use]
pub fn common_prefix(a: &[LlamaToken], b: &[LlamaToken]) -> usize {
    a.iter().zip(b).take_while(|(x, y)| x == y).count()
}

fn read_tokens(path: &Path) -> Option<Vec<LlamaToken>> {
    let bytes = fs::read(path).ok()?;
    if bytes.len() % 4 != 0 {
        return None;
    }
    Some(
        bytes
            .chunks_exact(4)
            .map(|c| LlamaToken(i32::from_le_bytes([c[0], c[1], c[2], c[3]])))
            .collect(),
    )
}

impl DiskCache {
    /// Opens (creating it) the folder for `model` evaluated under `settings` (what
    /// changes the numbers a prefix evaluates to, e.g. `t2-b512`) under `root` and reads
    /// its entries' token lists. `None` when the folder cannot be made or the model
    /// cannot be read: the cache is an optimisation, never a reason to fail.
    #[must_use]
    pub fn open(root: &Path, model: &Path, settings: &str) -> Option<Self> {
        let dir = root.join(model_key(model, settings)?);
        if let Err(e) = fs::create_dir_all(&dir) {
            tracing::warn!(dir = %dir.display(), error = %e, "prompt cache off: cannot create its folder");
            return None;
        }
        let mut entries = Vec::new();
        if let Ok(rd) = fs::read_dir(&dir) {
            for f in rd.flatten() {
                let kv = f.path();
                if kv.extension().is_some_and(|x| x == "kv") {
                    if let Some(tokens) = read_tokens(&kv.with_extension("tokens")) {
                        if !tokens.is_empty() {
                            entries.push(Entry { kv, tokens });
                        }
                    }
                }
            }
        }
        entries.sort_by(|a, b| a.kv.cmp(&b.kv));
        Some(Self {
            dir,
            entries,
            recent: Vec::new(),
        })
    }

    /// The entry sharing the longest prefix with `tokens`, and that length, if at least
    /// [`MIN_TOKENS`].
    #[must_use]
    pub fn best(&self, tokens: &[LlamaToken]) -> Option<(&Entry, usize)> {
        self.entries
            .iter()
            .map(|e| (e, common_prefix(&e.tokens, tokens)))
            .filter(|(_, n)| *n >= MIN_TOKENS)
            .max_by_key(|(_, n)| *n)
    }

    /// Whether a prefix of `n` tokens of `tokens` is worth saving: long enough, and at
    /// least [`MIN_TOKENS`] more than any entry gives of it (so that prefixes differing
    /// only in a short tail, such as the map line of one request, do not fill the folder).
    #[must_use]
    pub fn wants(&self, tokens: &[LlamaToken], n: usize) -> bool {
        n >= MIN_TOKENS
            && self
                .best(tokens)
                .is_none_or(|(_, have)| have + MIN_TOKENS <= n)
    }

    /// The longest prefix `tokens` shares with one of the last [`RECENT_PROMPTS`] prompts
    /// passed here (0 for none); then remembers `tokens`.
    pub fn asked_before(&mut self, tokens: &[LlamaToken]) -> usize {
        let shared = self
            .recent
            .iter()
            .map(|r| common_prefix(r, tokens))
            .max()
            .unwrap_or(0);
        self.recent.push(tokens.to_vec());
        if self.recent.len() > RECENT_PROMPTS {
            self.recent.remove(0);
        }
        shared
    }

    /// A fresh path for a new snapshot (`<n>.kv`, `n` past every entry's).
    #[must_use]
    pub fn next_path(&self) -> PathBuf {
        let next = self
            .entries
            .iter()
            .filter_map(|e| e.kv.file_stem()?.to_str()?.parse::<u64>().ok())
            .max()
            .map_or(0, |n| n + 1);
        self.dir.join(format!("{next:06}.kv"))
    }

    /// Records a snapshot llama.cpp has written to `kv` (see [`Self::next_path`]): writes
    /// its token list, then drops the oldest entries beyond [`MAX_ENTRIES`].
    pub fn add(&mut self, kv: PathBuf, tokens: &[LlamaToken]) {
        let bytes: Vec<u8> = tokens.iter().flat_map(|t| t.0.to_le_bytes()).collect();
        let entry = Entry {
            kv,
            tokens: tokens.to_vec(),
        };
        // The token list last, and by rename: an entry is complete once it is there.
        let tmp = entry.kv.with_extension("tokens.tmp");
        if let Err(e) = fs::write(&tmp, &bytes).and_then(|()| fs::rename(&tmp, entry.sidecar())) {
            tracing::warn!(file = %tmp.display(), error = %e, "prompt cache: cannot write a token list");
            let _ = fs::remove_file(&entry.kv);
            return;
        }
        self.entries.push(entry);
        while self.entries.len() > MAX_ENTRIES {
            let old = self.entries.remove(0);
            self.remove_files(&old);
        }
    }

    /// Forgets an entry llama.cpp would not load, and deletes its files.
    pub fn discard(&mut self, kv: &Path) {
        if let Some(i) = self.entries.iter().position(|e| e.kv == kv) {
            let old = self.entries.remove(i);
            self.remove_files(&old);
        }
    }

    fn remove_files(&self, e: &Entry) {
        let _ = fs::remove_file(e.sidecar());
        let _ = fs::remove_file(&e.kv);
    }

    /// How many entries there are.
    #[cfg(test)]
    #[must_use]
    pub fn len(&self) -> usize {
        self.entries.len()
    }

    /// Whether there is none.
    #[cfg(test)]
    #[must_use]
    pub fn is_empty(&self) -> bool {
        self.entries.is_empty()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn toks(v: impl IntoIterator<Item = i32>) -> Vec<LlamaToken> {
        v.into_iter().map(LlamaToken).collect()
    }

    fn tempdir(name: &str) -> PathBuf {
        let d =
            std::env::temp_dir().join(format!("ivlmap-disk-cache-{name}-{}", std::process::id()));
        let _ = fs::remove_dir_all(&d);
        fs::create_dir_all(&d).unwrap();
        d
    }

    #[test]
    fn entries_survive_a_reopen_and_the_longest_shared_prefix_wins() {
        let root = tempdir("reopen");
        let model = root.join("m.gguf");
        fs::write(&model, b"not really a model").unwrap();
        let mut c = DiskCache::open(&root, &model, "t2-b512").unwrap();
        assert!(c.is_empty());
        let a = toks(0..600);
        let b = toks((0..550).chain(1000..1100));
        for t in [&a, &b] {
            let kv = c.next_path();
            fs::write(&kv, b"snapshot").unwrap();
            c.add(kv, t);
        }
        let c = DiskCache::open(&root, &model, "t2-b512").unwrap();
        assert_eq!(c.len(), 2);
        let prompt = toks((0..550).chain(1000..1050).chain(7..9));
        let (e, n) = c.best(&prompt).unwrap();
        assert_eq!(n, 600);
        assert_eq!(e.tokens, b);
        // Too short a match is no match; a prefix an entry covers is not saved again.
        assert!(c.best(&toks(0..100)).is_none());
        assert!(!c.wants(&prompt, 580));
        assert!(!c.wants(&toks((0..550).chain(1000..1100).chain(5..9)), 604));
        let longer = toks((0..550).chain(1000..1100).chain(5000..6000));
        assert!(c.wants(&longer, 1200));
        assert!(!c.wants(&toks(0..400), 400));
        let _ = fs::remove_dir_all(&root);
    }

    #[test]
    fn prompts_asked_before_are_remembered_up_to_a_limit() {
        let root = tempdir("recent");
        let model = root.join("m.gguf");
        fs::write(&model, b"x").unwrap();
        let mut c = DiskCache::open(&root, &model, "t2-b512").unwrap();
        assert_eq!(c.asked_before(&toks(0..600)), 0);
        assert_eq!(c.asked_before(&toks((0..550).chain(900..950))), 550);
        for k in 0..RECENT_PROMPTS as i32 {
            c.asked_before(&toks((0..10).map(|i| i + 10_000 * (k + 1))));
        }
        assert_eq!(
            c.asked_before(&toks(0..600)),
            0,
            "forgotten after the limit"
        );
        let _ = fs::remove_dir_all(&root);
    }

    #[test]
    fn old_entries_go_and_unloadable_ones_are_deleted() {
        let root = tempdir("evict");
        let model = root.join("m.gguf");
        fs::write(&model, b"x").unwrap();
        let mut c = DiskCache::open(&root, &model, "t2-b512").unwrap();
        let mut first = None;
        for k in 0..(MAX_ENTRIES as i32 + 2) {
            let kv = c.next_path();
            fs::write(&kv, b"s").unwrap();
            first.get_or_insert(kv.clone());
            c.add(kv, &toks((0..600).map(|i| i + k * 1000)));
        }
        assert_eq!(c.len(), MAX_ENTRIES);
        assert!(!first.unwrap().exists(), "the oldest snapshot is removed");
        let newest = c.entries.last().unwrap().kv.clone();
        c.discard(&newest);
        assert_eq!(c.len(), MAX_ENTRIES - 1);
        assert!(!newest.exists() && !newest.with_extension("tokens").exists());
        let _ = fs::remove_dir_all(&root);
    }

    #[test]
    fn a_changed_model_gets_another_folder_and_a_torn_token_list_is_ignored() {
        let root = tempdir("key");
        let model = root.join("m.gguf");
        fs::write(&model, b"one").unwrap();
        let mut c = DiskCache::open(&root, &model, "t2-b512").unwrap();
        let kv = c.next_path();
        fs::write(&kv, b"s").unwrap();
        c.add(kv.clone(), &toks(0..600));
        fs::write(kv.with_extension("tokens"), [1u8, 2, 3]).unwrap();
        assert!(DiskCache::open(&root, &model, "t2-b512")
            .unwrap()
            .is_empty());
        fs::write(&model, b"a longer model").unwrap();
        let other = DiskCache::open(&root, &model, "t2-b512").unwrap();
        assert!(other.is_empty());
        assert_ne!(other.dir, c.dir);
        // Another thread count or batch size: another folder.
        let t1 = DiskCache::open(&root, &model, "t1-b512").unwrap();
        assert_ne!(t1.dir, other.dir);
        let _ = fs::remove_dir_all(&root);
    }
}
