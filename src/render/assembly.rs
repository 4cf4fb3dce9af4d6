//! Packet assembly of secondary rays (Boulos et al. 2007 §3.2): how the shadow, reflection and
//! refraction rays spawned by one incoming packet are grouped into outgoing packets. The property
//! runs and groups share is the material the parent ray hit (§3.2.1).
//!
//! - `none`: every secondary ray is a packet of its own (single-ray tracing).
//! - `runs`: rays of one kind whose parents hit the same material and are adjacent in the
//!   incoming packet (or are the same parent: one shadow ray per light).
//! - `groups`: rays of one kind whose parents hit the same material, adjacent or not.
//! - `ray_types`: one packet per kind (shadow, reflection, refraction).
//! - `blind`: one packet of all secondary rays. Such a packet mixes occlusion and closest-hit
//!   queries, so the Whitted renderer puts it in one mixed batch traced with closest-hit calls and
//!   reads a shadow ray's answer as "occluded" when it hit anything within its interval — the
//!   same answer an occlusion call gives, at the price of a closest-hit search (part of what
//!   §3.2.1 holds against blind assembly).

use std::fmt;

use crate::geometry::RayKind;

/// The secondary kinds, in the order their packets are produced.
pub const SECONDARY_KINDS: [RayKind; 3] =
    [RayKind::Shadow, RayKind::Reflection, RayKind::Refraction];

#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum Assembly {
    None,
    Runs,
    Groups,
    RayTypes,
    Blind,
}

impl Assembly {
    pub const ALL: [Assembly; 5] = [
        Assembly::None,
        Assembly::Runs,
        Assembly::Groups,
        Assembly::RayTypes,
        Assembly::Blind,
    ];

    pub fn name(self) -> &'static str {
        match self {
            Assembly::None => "none",
            Assembly::Runs => "runs",
            Assembly::Groups => "groups",
            Assembly::RayTypes => "ray_types",
            Assembly::Blind => "blind",
        }
    }

    pub fn parse(name: &str) -> Option<Assembly> {
        Self::ALL.into_iter().find(|a| a.name() == name)
    }

    pub fn names() -> String {
        Self::ALL.map(|a| a.name()).join(", ")
    }
}

impl fmt::Display for Assembly {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

/// Which batch an outgoing packet joins: the batch of its ray kind, or the one mixed batch of
/// blind assembly.
#[derive(
    Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord, serde::Serialize, serde::Deserialize,
)]
pub enum BatchKind {
    Rays(RayKind),
    Blind,
}

impl BatchKind {
    /// The runs.csv `ray_kind` of the batch.
    pub fn name(self) -> &'static str {
        match self {
            BatchKind::Rays(kind) => kind.name(),
            BatchKind::Blind => "blind",
        }
    }
}

/// A secondary ray waiting for a packet: the index of its parent in the incoming packet, the
/// material the parent hit, its kind and, for a shadow ray, the light it goes to (0 otherwise).
/// Candidates come in parent order.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Candidate {
    pub parent: usize,
    pub material: u32,
    pub kind: RayKind,
    pub light: u32,
}

/// The outgoing packets of one incoming packet, in buffers the caller keeps from packet to packet
/// (no allocation per packet, or per ray with `none`): every packet's members (indices into the
/// candidate list) one packet after another, and where each packet ends.
#[derive(Clone, Debug, Default)]
pub struct OutPackets {
    members: Vec<usize>,
    /// Per packet: the batch it joins and the end of its members.
    packets: Vec<(BatchKind, usize)>,
    /// Scratch: group keys in order of first appearance.
    keys: Vec<u32>,
}

impl OutPackets {
    /// The packets in order: the batch each joins and its members in candidate order.
    pub fn iter(&self) -> impl Iterator<Item = (BatchKind, &[usize])> + '_ {
        let starts = std::iter::once(0).chain(self.packets.iter().map(|&(_, end)| end));
        self.packets
            .iter()
            .zip(starts)
            .map(|(&(batch, end), start)| (batch, &self.members[start..end]))
    }

    pub fn is_empty(&self) -> bool {
        self.packets.is_empty()
    }

    /// The members pushed since the last packet ended.
    fn open(&self) -> &[usize] {
        let start = self.packets.last().map_or(0, |&(_, end)| end);
        &self.members[start..]
    }

    /// Ends the open packet as one of `batch`, unless it is empty.
    fn close(&mut self, batch: BatchKind) {
        if !self.open().is_empty() {
            self.packets.push((batch, self.members.len()));
        }
    }
}

/// The outgoing packets of one incoming packet's `candidates` into `out` (replacing what it held):
/// per kind in `SECONDARY_KINDS` order (blind: one packet), each packet's members in candidate
/// order.
pub fn assemble(method: Assembly, candidates: &[Candidate], out: &mut OutPackets) {
    out.members.clear();
    out.packets.clear();
    let of_kind = |kind: RayKind| {
        candidates
            .iter()
            .enumerate()
            .filter(move |(_, c)| c.kind == kind)
    };
    match method {
        Assembly::None => {
            for kind in SECONDARY_KINDS {
                for (i, _) in of_kind(kind) {
                    out.members.push(i);
                    out.close(BatchKind::Rays(kind));
                }
            }
        }
        Assembly::Blind => {
            out.members.extend(0..candidates.len());
            out.close(BatchKind::Blind);
        }
        Assembly::RayTypes => {
            // Shadow rays toward each light are a type of their own: Boulos's Fig. 3 has one
            // light; with several, one packet mixing them has no common end point (no §4.2
            // frustum) and spreads over every light's direction.
            for kind in SECONDARY_KINDS {
                grouped(out, kind, candidates, |c| c.light);
            }
        }
        Assembly::Runs => {
            for kind in SECONDARY_KINDS {
                for (i, c) in of_kind(kind) {
                    let continues = out.open().last().is_some_and(|&last| {
                        let prev = &candidates[last];
                        prev.material == c.material && c.parent - prev.parent <= 1
                    });
                    if !continues {
                        out.close(BatchKind::Rays(kind));
                    }
                    out.members.push(i);
                }
                out.close(BatchKind::Rays(kind));
            }
        }
        Assembly::Groups => {
            for kind in SECONDARY_KINDS {
                grouped(out, kind, candidates, |c| c.material);
            }
        }
    }
}

/// One packet of `kind` per distinct `key` among the `candidates` of that kind, in order of first
/// appearance, each with its members in candidate order.
fn grouped(
    out: &mut OutPackets,
    kind: RayKind,
    candidates: &[Candidate],
    key: impl Fn(&Candidate) -> u32,
) {
    let of_kind = || {
        candidates
            .iter()
            .enumerate()
            .filter(|(_, c)| c.kind == kind)
    };
    // One pass per key over the candidates (a handful of materials or lights) rather than a
    // member list per group.
    out.keys.clear();
    for (_, c) in of_kind() {
        if !out.keys.contains(&key(c)) {
            out.keys.push(key(c));
        }
    }
    for g in 0..out.keys.len() {
        let k = out.keys[g];
        out.members
            .extend(of_kind().filter(|(_, c)| key(c) == k).map(|(i, _)| i));
        out.close(BatchKind::Rays(kind));
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const DIFFUSE: u32 = 0;
    const FLOOR: u32 = 1;
    const METAL: u32 = 2;
    const GLASS: u32 = 3;

    /// Boulos et al. 2007, Figure 3: 16 primary rays (numbered 1–16 in the paper, 0–15 here).
    /// 1–4 hit diffuse surfaces (shadow only); 5–6 the floor (reflection and shadow); 7, 8, 11, 12
    /// the metal teapot (reflection only); the others glass (reflection and refraction).
    fn figure_3() -> Vec<Candidate> {
        let material = |ray: usize| match ray {
            1..=4 => DIFFUSE,
            5 | 6 => FLOOR,
            7 | 8 | 11 | 12 => METAL,
            _ => GLASS,
        };
        let mut candidates = Vec::new();
        for ray in 1..=16 {
            let m = material(ray);
            let kinds: &[RayKind] = match m {
                DIFFUSE => &[RayKind::Shadow],
                FLOOR => &[RayKind::Shadow, RayKind::Reflection],
                METAL => &[RayKind::Reflection],
                _ => &[RayKind::Reflection, RayKind::Refraction],
            };
            candidates.extend(kinds.iter().map(|&kind| Candidate {
                parent: ray - 1,
                material: m,
                kind,
                light: 0,
            }));
        }
        candidates
    }

    /// The packets as (kind, paper ray numbers).
    fn packets(method: Assembly) -> Vec<(&'static str, Vec<usize>)> {
        let candidates = figure_3();
        let mut out = OutPackets::default();
        assemble(method, &candidates, &mut out);
        out.iter()
            .map(|(batch, members)| {
                let rays = members.iter().map(|&i| candidates[i].parent + 1);
                (batch.name(), rays.collect())
            })
            .collect()
    }

    #[test]
    fn figure_3_runs_groups_and_ray_types_match_section_3_2_1() {
        // 6 shadow, 12 reflection and 6 refraction rays (§3.2).
        let candidates = figure_3();
        let count = |k| candidates.iter().filter(|c| c.kind == k).count();
        let counts = [RayKind::Shadow, RayKind::Reflection, RayKind::Refraction].map(count);
        assert_eq!(counts, [6, 12, 6]);

        let (s, rl, rr) = ("shadow", "reflection", "refraction");
        assert_eq!(
            packets(Assembly::Runs),
            vec![
                (s, vec![1, 2, 3, 4]),
                (s, vec![5, 6]),
                (rl, vec![5, 6]),
                (rl, vec![7, 8]),
                (rl, vec![9, 10]),
                (rl, vec![11, 12]),
                (rl, vec![13, 14, 15, 16]),
                (rr, vec![9, 10]),
                (rr, vec![13, 14, 15, 16]),
            ]
        );
        assert_eq!(
            packets(Assembly::Groups),
            vec![
                (s, vec![1, 2, 3, 4]),
                (s, vec![5, 6]),
                (rl, vec![5, 6]),
                (rl, vec![7, 8, 11, 12]),
                (rl, vec![9, 10, 13, 14, 15, 16]),
                (rr, vec![9, 10, 13, 14, 15, 16]),
            ]
        );
        assert_eq!(
            packets(Assembly::RayTypes),
            vec![
                (s, vec![1, 2, 3, 4, 5, 6]),
                (rl, (5..=16).collect()),
                (rr, vec![9, 10, 13, 14, 15, 16]),
            ]
        );
    }

    #[test]
    fn figure_3_single_rays_and_blind() {
        let single = packets(Assembly::None);
        assert_eq!(single.len(), 24);
        assert!(single.iter().all(|(_, rays)| rays.len() == 1));
        let blind = packets(Assembly::Blind);
        assert_eq!(blind.len(), 1);
        assert_eq!(blind[0].0, "blind");
        assert_eq!(blind[0].1.len(), 24);
        // A reused buffer holds only the latest packets.
        let mut out = OutPackets::default();
        assemble(Assembly::None, &figure_3(), &mut out);
        assemble(Assembly::Blind, &[], &mut out);
        assert!(out.is_empty());
    }

    #[test]
    fn runs_keep_the_shadow_rays_of_one_parent_together() {
        // Two lights: parent 0 spawns two shadow rays, parent 1 two more, parent 3 (not adjacent) two.
        let c = |parent, light| Candidate {
            parent,
            material: 0,
            kind: RayKind::Shadow,
            light,
        };
        let candidates = [c(0, 0), c(0, 1), c(1, 0), c(1, 1), c(3, 0), c(3, 1)];
        let members = |method| -> Vec<Vec<usize>> {
            let mut out = OutPackets::default();
            assemble(method, &candidates, &mut out);
            out.iter().map(|(_, members)| members.to_vec()).collect()
        };
        assert_eq!(members(Assembly::Runs), vec![vec![0, 1, 2, 3], vec![4, 5]]);
        // Ray types: one shadow packet per light.
        assert_eq!(
            members(Assembly::RayTypes),
            vec![vec![0, 2, 4], vec![1, 3, 5]]
        );
        assert_eq!(Assembly::parse("ray_types"), Some(Assembly::RayTypes));
        assert_eq!(Assembly::parse("rays"), None);
    }
}
