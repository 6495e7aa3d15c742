//! The read planner is exact: on random small cases its plan costs exactly as little as the
//! cheapest plan an exhaustive search finds, and it is a valid plan (only readable addresses,
//! at most `max_read` per request, every wanted address read).
//!
//! The exhaustive search does not share the planner's reasoning: it takes the lowest wanted
//! address not yet read and tries every request that could read it — every start and every end,
//! wanted or not, as long as every address in between may be read and the quantity is at most
//! `max_read` — then recurses. Requests may overlap. It prunes a branch only when its partial
//! cost already reaches the best complete plan found, which is sound because costs are not
//! negative.
//!
//! The cases come from a fixed-seed generator, so every run checks the same cases.

use drivemap_runtime::bus_time::{BusModel, SerialConfig};
use drivemap_runtime::core::profile::Parity;
use drivemap_runtime::core::profile::Profile;
use drivemap_runtime::planner::{ReadableSet, plan_contiguous, plan_cost, plan_reads, plan_single};
use drivemap_test_support::rng::SplitMix;

struct Case {
    base: u16,
    /// readable[i]: base + i may be read.
    readable: Vec<bool>,
    wanted: Vec<u16>,
    max_read: u16,
    /// cost[q] for q in 1..=max_read (cost[0] unused).
    cost: Vec<u64>,
    family: &'static str,
}

fn model_cost(rng: &mut SplitMix, max_read: u16) -> Vec<u64> {
    let bauds = [1200, 2400, 4800, 9600, 19_200, 38_400, 115_200];
    let parity = [Parity::None, Parity::Even, Parity::Odd][rng.below(3) as usize];
    let serial = SerialConfig::new(bauds[rng.below(bauds.len() as u64) as usize]).parity(parity);
    let ids = [
        "yaskawa-v7",
        "yaskawa-j7",
        "automationdirect-acn",
        "ptlk-tds-v8",
        "generic",
    ];
    let mut profile = Profile {
        drive_id: ids[rng.below(ids.len() as u64) as usize],
        ..Profile::GENERIC
    };
    if rng.chance(30) {
        profile.timing.response_delay_us = Some(rng.below(20_000) as u32);
    }
    let model = BusModel::new(&profile, serial);
    (0..=max_read)
        .map(|q| if q == 0 { 0 } else { model.read_ns(q) })
        .collect()
}

fn draw(rng: &mut SplitMix) -> Case {
    let n = 1 + rng.below(12) as usize;
    let base = match rng.below(4) {
        0 => 0,
        1 => 0xFFFF - (n as u16 - 1), // the top of the address space
        _ => rng.below(0x1000) as u16,
    };
    let density = 40 + rng.below(60);
    let readable: Vec<bool> = (0..n).map(|_| rng.chance(density)).collect();
    let want = 20 + rng.below(80);
    let mut wanted: Vec<u16> = (0..n)
        .filter(|&i| readable[i] && rng.chance(want))
        .map(|i| base + i as u16)
        .collect();
    // Duplicates and any order are allowed in the input.
    if wanted.len() > 1 && rng.chance(30) {
        wanted.push(wanted[0]);
        wanted.reverse();
    }
    let max_read = 1 + rng.below(8) as u16;
    let (cost, family) = match rng.below(4) {
        0 => (model_cost(rng, max_read), "bus-time model"),
        1 => {
            let fixed = rng.below(100);
            let per = rng.below(20);
            (
                (0..=max_read)
                    .map(|q| {
                        if q == 0 {
                            0
                        } else {
                            fixed + per * u64::from(q)
                        }
                    })
                    .collect(),
                "affine",
            )
        }
        2 => {
            let mut c = vec![0u64; usize::from(max_read) + 1];
            let mut acc = rng.below(50);
            for slot in c.iter_mut().skip(1) {
                acc += rng.below(30);
                *slot = acc;
            }
            (c, "non-decreasing")
        }
        _ => (
            (0..=max_read)
                .map(|q| if q == 0 { 0 } else { rng.below(60) })
                .collect(),
            "arbitrary",
        ),
    };
    Case {
        base,
        readable,
        wanted,
        max_read,
        cost,
        family,
    }
}

fn exhaustive(case: &Case) -> u64 {
    let mut wanted = case.wanted.clone();
    wanted.sort_unstable();
    wanted.dedup();
    let offsets: Vec<usize> = wanted.iter().map(|&a| usize::from(a - case.base)).collect();
    let mut best = u64::MAX;
    search(case, &offsets, 0, 0, &mut best);
    best
}

fn search(case: &Case, wanted: &[usize], next: usize, partial: u64, best: &mut u64) {
    if partial >= *best {
        return;
    }
    let Some(&w) = wanted.get(next) else {
        *best = partial;
        return;
    };
    let n = case.readable.len();
    let max = usize::from(case.max_read);
    for start in 0..=w {
        for end in w..n {
            let quantity = end - start + 1;
            if quantity > max {
                break;
            }
            if !case.readable[start..=end].iter().all(|&r| r) {
                continue;
            }
            let after = wanted[next..]
                .iter()
                .position(|&a| a > end)
                .map_or(wanted.len(), |p| next + p);
            search(case, wanted, after, partial + case.cost[quantity], best);
        }
    }
}

#[test]
fn the_planner_is_exact_against_exhaustive_search() {
    const CASES: usize = 20_000;
    let mut rng = SplitMix(0x5EED_2024_0008);
    let mut per_family: std::collections::BTreeMap<&str, (usize, usize)> = Default::default();
    let mut strictly_better_than_contiguous = 0;
    for index in 0..CASES {
        let case = draw(&mut rng);
        let readable = ReadableSet::new(
            case.readable
                .iter()
                .enumerate()
                .filter(|(_, r)| **r)
                .map(|(i, _)| case.base + i as u16),
        );
        let cost = |q: u16| case.cost[usize::from(q)];
        let plan = plan_reads(&case.wanted, &readable, case.max_read, cost)
            .unwrap_or_else(|e| panic!("case {index}: {e}"));

        // Valid: readable, within max_read, every wanted address read.
        for r in &plan {
            assert!(
                r.quantity >= 1 && r.quantity <= case.max_read,
                "case {index}: {r:?}"
            );
            for a in u32::from(r.address)..=u32::from(r.last()) {
                assert!(
                    readable.contains(a as u16),
                    "case {index}: {r:?} reads {a:04X}h, which may not be read"
                );
            }
        }
        for &a in &case.wanted {
            assert!(
                plan.iter().any(|r| r.contains(a)),
                "case {index}: {a:04X}h not read by {plan:?}"
            );
        }

        // Optimal.
        let optimum = exhaustive(&case);
        let planned = plan_cost(&plan, cost);
        assert_eq!(
            planned, optimum,
            "case {index} ({}): plan {plan:?} costs {planned}, exhaustive search finds {optimum}; \
             readable {:?} from {:04X}h, wanted {:?}, max_read {}, cost {:?}",
            case.family, case.readable, case.base, case.wanted, case.max_read, case.cost
        );

        // The baselines never beat it.
        let contiguous = plan_cost(&plan_contiguous(&case.wanted, case.max_read), cost);
        let single = plan_cost(&plan_single(&case.wanted), cost);
        assert!(planned <= contiguous && planned <= single, "case {index}");
        if planned < contiguous {
            strictly_better_than_contiguous += 1;
        }
        let e = per_family.entry(case.family).or_default();
        e.0 += 1;
        e.1 += usize::from(!case.wanted.is_empty());
    }
    println!("{CASES} cases, per cost family (cases, with wanted registers): {per_family:?}");
    println!("plans strictly cheaper than contiguous runs: {strictly_better_than_contiguous}");
    // The draw covers every cost family and the planner's advantage actually occurs.
    assert_eq!(per_family.len(), 4);
    assert!(per_family.values().all(|&(n, w)| n > 2_000 && w > 1_000));
    assert!(strictly_better_than_contiguous > 1_000);
}
