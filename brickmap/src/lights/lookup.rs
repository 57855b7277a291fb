//! Face → slot lookup: an open-addressing hash table (linear probing, at most half full) of
//! slot + 1 (0: empty), keyed by the face's voxel and direction, whose keys are read from
//! the face records. A BSDF ray that hits a light face finds its slot here to weigh itself
//! against light sampling (the tree's probability of a face depends on its slot's path).
//! shaders/lights.glsl probes the same way; keep the hash in step.

/// The hash of a face record's key (its first word: x | z << 12 | face << 24, and y).
pub fn face_hash(w0: u32, y: u32) -> u32 {
    fn mix(mut x: u32) -> u32 {
        x = x.wrapping_mul(747_796_405).wrapping_add(2_891_336_453);
        x = ((x >> ((x >> 28) + 4)) ^ x).wrapping_mul(277_803_737);
        (x >> 22) ^ x
    }
    mix(w0 ^ mix(y))
}

/// The key words of a face record (its material left out).
pub(crate) fn key(record: [u32; 2]) -> (u32, u32) {
    (record[0], record[1] & 0xFFFF)
}

/// The table: `entries.len()` is a power of two, twice the slot capacity.
#[derive(Clone, Debug, Default)]
pub(crate) struct FaceTable {
    pub(crate) entries: Vec<u32>,
}

impl FaceTable {
    pub(crate) fn with_len(len: usize) -> Self {
        Self {
            entries: vec![0; len],
        }
    }

    fn mask(&self) -> usize {
        self.entries.len() - 1
    }

    fn home(&self, faces: &[[u32; 2]], entry: u32) -> usize {
        let (w0, y) = key(faces[entry as usize - 1]);
        face_hash(w0, y) as usize & self.mask()
    }

    /// The slot holding the face with key (w0, y), if any.
    pub(crate) fn find(&self, faces: &[[u32; 2]], w0: u32, y: u32) -> Option<u32> {
        let mut i = face_hash(w0, y) as usize & self.mask();
        loop {
            let e = self.entries[i];
            if e == 0 {
                return None;
            }
            if key(faces[e as usize - 1]) == (w0, y) {
                return Some(e - 1);
            }
            i = (i + 1) & self.mask();
        }
    }

    /// Enters `slot` (its face record already written); returns the entry written.
    pub(crate) fn insert(&mut self, faces: &[[u32; 2]], slot: u32) -> usize {
        let mut i = self.home(faces, slot + 1);
        while self.entries[i] != 0 {
            i = (i + 1) & self.mask();
        }
        self.entries[i] = slot + 1;
        i
    }

    /// Takes `slot` out (its face record still the one it was entered with), moving later
    /// entries of its probe run back so that no lookup passes a hole (no tombstones);
    /// `changed` receives every entry written.
    pub(crate) fn remove(&mut self, faces: &[[u32; 2]], slot: u32, changed: &mut Vec<usize>) {
        let (w0, y) = key(faces[slot as usize]);
        let mut i = face_hash(w0, y) as usize & self.mask();
        while self.entries[i] != slot + 1 {
            debug_assert!(self.entries[i] != 0, "slot {slot} is not in the table");
            if self.entries[i] == 0 {
                return;
            }
            i = (i + 1) & self.mask();
        }
        let mut j = i;
        loop {
            j = (j + 1) & self.mask();
            let e = self.entries[j];
            if e == 0 {
                break;
            }
            // Entry j may move to the hole at i unless its home lies cyclically in (i, j].
            let k = self.home(faces, e);
            let stays = if i <= j {
                i < k && k <= j
            } else {
                i < k || k <= j
            };
            if !stays {
                self.entries[i] = e;
                changed.push(i);
                i = j;
            }
        }
        self.entries[i] = 0;
        changed.push(i);
    }
}
