//! The island solve's team of threads and its cut (src/sim/parallel.rs).

use std::panic::{catch_unwind, AssertUnwindSafe};
use std::sync::atomic::{AtomicUsize, Ordering};
use std::time::Duration;
use urdyn::testing::parallel::{cut, Team};

#[test]
fn every_item_is_done_once_whoever_takes_it() {
    let team = Team::new(3).expect("a team of three");
    assert_eq!(team.threads(), 3);
    for round in 0..300 {
        let items: Vec<AtomicUsize> = (0..64).map(|_| AtomicUsize::new(0)).collect();
        let next = AtomicUsize::new(0);
        team.run(&|_| loop {
            let i = next.fetch_add(1, Ordering::Relaxed);
            let Some(x) = items.get(i) else { break };
            x.fetch_add(1, Ordering::Relaxed);
        });
        assert!(
            items.iter().all(|h| h.load(Ordering::Relaxed) == 1),
            "round {round}"
        );
        if round % 100 == 0 {
            // long enough for the workers to fall asleep: the next job's
            // dispatch wakes them
            std::thread::sleep(Duration::from_millis(2));
        }
    }
}

#[test]
fn part_zero_runs_here_and_its_panic_reaches_the_caller() {
    let team = Team::new(2).expect("a team of two");
    let here = std::thread::current().id();
    let r = catch_unwind(AssertUnwindSafe(|| {
        team.run(&|k| {
            if k == 0 {
                assert_eq!(std::thread::current().id(), here);
                panic!("part 0");
            }
        })
    }));
    assert!(r.is_err());
    // the team goes on
    let n = AtomicUsize::new(0);
    team.run(&|k| {
        if k == 0 {
            n.fetch_add(1, Ordering::Relaxed);
        }
    });
    assert_eq!(n.load(Ordering::Relaxed), 1);
}

#[test]
fn the_cut_orders_largest_first_and_keeps_small_jobs_here() {
    let mut order = Vec::new();
    let sizes = [10, 50, 40, 10, 30, 20];
    // 50 + 20 + 10 against 40 + 30 + 10: 80 off one thread's 160
    assert!(cut(&sizes, 2, 80, &mut order));
    let js: Vec<usize> = order.iter().map(|x| x.1).collect();
    assert_eq!(js, [1, 2, 4, 5, 0, 3]);
    assert!(!cut(&sizes, 2, 81, &mut order));
    // one island: nothing to share
    assert!(!cut(&[500], 2, 10, &mut order));
    assert!(!cut(&sizes, 1, 10, &mut order));
}

#[test]
fn a_worker_that_holds_the_caller_up_costs_a_few_jobs_alone() {
    use std::sync::atomic::AtomicBool;
    use std::time::Instant;
    let team = Team::new(2).expect("a team of two");
    // a worker in the job holds the caller up for 50 ms (as one descheduled
    // in the middle of an item would): far over the caller's own part
    let inside = AtomicBool::new(false);
    let late = AtomicBool::new(false);
    team.run(&|k| {
        if k == 0 {
            let t = Instant::now();
            while !inside.load(Ordering::Acquire) && t.elapsed() < Duration::from_secs(2) {
                std::hint::spin_loop();
            }
            late.store(t.elapsed() > Duration::from_millis(20), Ordering::Relaxed);
        } else {
            inside.store(true, Ordering::Release);
            std::thread::sleep(Duration::from_millis(50));
        }
    });
    if !inside.load(Ordering::Acquire) || late.load(Ordering::Relaxed) {
        // the worker came late or never (a very loaded machine): the caller's
        // own part was not short against the hold-up, nothing to check
        return;
    }
    // the next jobs (the cool-down's first length, 4) run on this thread alone
    for job in 0..4 {
        let others = AtomicUsize::new(0);
        team.run(&|k| {
            if k != 0 {
                others.fetch_add(1, Ordering::Relaxed);
            }
            std::thread::sleep(Duration::from_micros(200));
        });
        assert_eq!(others.load(Ordering::Relaxed), 0, "job {job}");
    }
}
