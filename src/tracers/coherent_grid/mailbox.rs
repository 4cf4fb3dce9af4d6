//! Per-packet mailbox (Wald et al. 2006, §2.3 "Mailboxing"; Kirk and Arvo 1991): the triangles a
//! packet has already tested, so a triangle referenced by many of the cells the frustum overlaps is
//! tested once per packet.
//!
//! The paper tags each triangle with the packet's id, which needs a writable tag per triangle and
//! per thread. Here the tags live with the packet instead: an open-addressing hash set of triangle
//! ids whose slots carry the generation (packet) that wrote them, so clearing it for the next
//! packet is one increment, and it grows when a packet tests many triangles.

/// A slot: the triangle id and the generation that wrote it (a stale generation is an empty slot).
#[derive(Clone, Copy, Default)]
struct Slot {
    id: u32,
    generation: u32,
}

pub struct Mailbox {
    slots: Vec<Slot>,
    generation: u32,
    len: usize,
}

impl Default for Mailbox {
    fn default() -> Self {
        Mailbox::with_capacity(256)
    }
}

impl Mailbox {
    /// `capacity` is rounded up to a power of two.
    pub fn with_capacity(capacity: usize) -> Self {
        Mailbox {
            slots: vec![Slot::default(); capacity.next_power_of_two().max(16)],
            generation: 1,
            len: 0,
        }
    }

    /// Empties the set for the next packet.
    pub fn clear(&mut self) {
        self.len = 0;
        self.generation = self.generation.wrapping_add(1);
        if self.generation == 0 {
            // Generation 0 marks never-written slots: after wrapping, really clear them.
            self.slots.fill(Slot::default());
            self.generation = 1;
        }
    }

    /// Adds `id`; `false` when it was already there (the packet has tested that triangle).
    #[inline]
    pub fn insert(&mut self, id: u32) -> bool {
        // Keep the load at most 1/2 so probe sequences stay short.
        if 2 * (self.len + 1) > self.slots.len() {
            self.grow();
        }
        let mask = self.slots.len() - 1;
        // Fibonacci hashing spreads neighbouring ids (neighbouring triangles) over the table.
        let mut i = (id.wrapping_mul(0x9E37_79B9) >> 7) as usize & mask;
        loop {
            let slot = &mut self.slots[i];
            if slot.generation != self.generation {
                *slot = Slot {
                    id,
                    generation: self.generation,
                };
                self.len += 1;
                return true;
            }
            if slot.id == id {
                return false;
            }
            i = (i + 1) & mask;
        }
    }

    fn grow(&mut self) {
        let generation = self.generation;
        let live: Vec<u32> = self
            .slots
            .iter()
            .filter(|s| s.generation == generation)
            .map(|s| s.id)
            .collect();
        self.slots = vec![Slot::default(); self.slots.len() * 2];
        self.generation = 1;
        self.len = 0;
        for id in live {
            self.insert(id);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn remembers_ids_until_cleared_and_grows() {
        let mut m = Mailbox::with_capacity(16);
        assert!(m.insert(7));
        assert!(!m.insert(7));
        // Far more ids than the initial table holds (7 is not among them): new once, then known.
        for id in 0..1000 {
            assert!(m.insert(id * 3), "id {}", id * 3);
        }
        for id in 0..1000 {
            assert!(!m.insert(id * 3));
        }
        assert!(!m.insert(7));
        m.clear();
        assert!(m.insert(7));
        assert!(m.insert(0));
        assert!(!m.insert(0));
    }
}
