//! MatchPattern benchmark: `cargo bench --bench match_pattern`.
//!
//! Compares, in one run on the same inputs:
//! - baseline: the recursive algorithm of the specification's Appendix B, ported line by line for this
//!   benchmark only (wide strings, `toupper` for case-insensitive, `iswdigit` for `#`), with a budget
//!   of recursive calls so adversarial cases stop and are reported as ">=" the time the budget took;
//! - ours: `MatchPatternW` (compiles the pattern on every call), `OpcPatternMatchW` (a filter compiled
//!   once) and `MatchPatternA`;
//! - fnmatch: glibc `fnmatch` on the same strings in UTF-8, with `#` written as `[0-9]`, FNM_NOESCAPE,
//!   and FNM_CASEFOLD when case-insensitive. It runs in a child process with a time limit, because it
//!   backtracks exponentially on some adversarial patterns.
//!
//! Prints one table (nanoseconds per call or per item) with the ratios the goals are stated in, then
//! whether each goal is met.

#[cfg(unix)]
fn main() {
    bench::run();
}

#[cfg(not(unix))]
fn main() {
    println!("the MatchPattern benchmark compares against glibc fnmatch: run it on Linux");
}

#[cfg(unix)]
mod bench {
    use std::ffi::{c_int, CString};
    use std::hint::black_box;
    use std::ptr;
    use std::time::{Duration, Instant};

    use opccomn::pattern::{
        MatchPatternA, MatchPatternW, OpcPattern, OpcPatternCompileW, OpcPatternFree, OpcPatternMatchW,
    };

    extern "C" {
        fn iswdigit(wc: u32) -> c_int;
    }

    // ---- The baseline: the specification's sample, ported faithfully ----

    /// Timing rounds per contender; each reports its best round.
    const ROUNDS: usize = 5;

    /// Recursive calls the baseline may make per match before it is cut off.
    const BUDGET: u64 = 20_000_000;

    struct Budget(u64);

    fn convert_case(c: u16, case_sensitive: bool) -> u16 {
        if case_sensitive {
            c
        } else {
            // SAFETY: toupper accepts any int (glibc returns values outside its table unchanged).
            unsafe { libc::toupper(c as c_int) as u16 }
        }
    }

    /// The Appendix B sample. `None` when the call budget ran out. Only called with well-formed
    /// patterns: the sample reads past the end of an unclosed `[`.
    ///
    /// # Safety
    /// Both pointers must point at NUL-terminated UTF-16 strings; the pattern must have no unclosed `[`.
    #[inline(never)] // called once per item like the library's functions, not inlined into the loop
    unsafe fn baseline(mut s: *const u16, mut p: *const u16, cs: bool, budget: &mut Budget) -> Option<bool> {
        if budget.0 == 0 {
            return None;
        }
        budget.0 -= 1;
        // SAFETY (whole body): the sample's pointer walk, valid for the inputs described above.
        // SAFETY: NUL-terminated strings; well-formed pattern.
        unsafe {
            loop {
                let pc = convert_case(*p, cs);
                p = p.add(1);
                match pc {
                    0 => return Some(*s == 0),
                    0x2A /* '*' */ => {
                        while *s != 0 {
                            let here = s;
                            s = s.add(1);
                            if baseline(here, p, cs, budget)? {
                                return Some(true);
                            }
                        }
                        return baseline(s, p, cs, budget);
                    }
                    0x3F /* '?' */ => {
                        let c = *s;
                        s = s.add(1);
                        if c == 0 {
                            return Some(false);
                        }
                    }
                    0x5B /* '[' */ => {
                        let c = convert_case(*s, cs);
                        s = s.add(1);
                        if c == 0 {
                            return Some(false);
                        }
                        let mut l: u16 = 0;
                        if *p == 0x21 /* '!' */ {
                            p = p.add(1);
                            loop {
                                let mut e = convert_case(*p, cs);
                                p = p.add(1);
                                if e == 0 {
                                    break;
                                }
                                if e == 0x5D /* ']' */ {
                                    break;
                                }
                                if e == 0x2D /* '-' */ {
                                    e = convert_case(*p, cs);
                                    if e == 0 || e == 0x5D {
                                        return Some(false);
                                    }
                                    if c >= l && c <= e {
                                        return Some(false);
                                    }
                                }
                                l = e;
                                if c == e {
                                    return Some(false);
                                }
                            }
                        } else {
                            let mut e;
                            loop {
                                e = convert_case(*p, cs);
                                p = p.add(1);
                                if e == 0 {
                                    break;
                                }
                                if e == 0x5D {
                                    return Some(false);
                                }
                                if e == 0x2D {
                                    e = convert_case(*p, cs);
                                    if e == 0 || e == 0x5D {
                                        return Some(false);
                                    }
                                    if c >= l && c <= e {
                                        break;
                                    }
                                }
                                l = e;
                                if c == e {
                                    break;
                                }
                            }
                            while e != 0 && e != 0x5D {
                                e = *p;
                                p = p.add(1);
                            }
                        }
                    }
                    0x23 /* '#' */ => {
                        let c = *s;
                        s = s.add(1);
                        if iswdigit(c as u32) == 0 {
                            return Some(false);
                        }
                    }
                    _ => {
                        let c = convert_case(*s, cs);
                        s = s.add(1);
                        if c != pc {
                            return Some(false);
                        }
                    }
                }
            }
        }
    }

    // ---- Inputs ----

    fn wide(s: &str) -> Vec<u16> {
        s.encode_utf16().chain([0]).collect()
    }

    /// The pattern in fnmatch syntax: `#` becomes `[0-9]`; the rest of these patterns means the same.
    fn to_fnmatch(p: &str) -> CString {
        CString::new(p.replace('#', "[0-9]")).unwrap()
    }

    fn fnmatch_flags(cs: bool) -> c_int {
        libc::FNM_NOESCAPE | if cs { 0 } else { libc::FNM_CASEFOLD }
    }

    // ---- Timing ----

    /// Runs `pass` (which handles `items` calls) until at least `min` has passed; ns per call.
    fn time_per_call(items: usize, min: Duration, mut pass: impl FnMut()) -> f64 {
        let start = Instant::now();
        let mut passes = 0u64;
        while passes == 0 || start.elapsed() < min {
            pass();
            passes += 1;
        }
        start.elapsed().as_nanos() as f64 / (passes as f64 * items as f64)
    }

    /// Times the baseline on one call: ns per call, or `Err(ns)` when it hit the budget after `ns`.
    fn time_baseline(s: &[u16], p: &[u16], cs: bool, expected: bool) -> Result<f64, f64> {
        let mut reps = 0u64;
        let start = Instant::now();
        loop {
            let mut budget = Budget(BUDGET);
            // SAFETY: NUL-terminated strings; well-formed pattern.
            let r = unsafe { baseline(s.as_ptr(), p.as_ptr(), cs, &mut budget) };
            reps += 1;
            match r {
                None => return Err(start.elapsed().as_nanos() as f64 / reps as f64),
                Some(m) => assert_eq!(m, expected, "the baseline disagrees"),
            }
            if start.elapsed() >= Duration::from_millis(100) {
                return Ok(start.elapsed().as_nanos() as f64 / reps as f64);
            }
        }
    }

    /// Runs `f` in a child process, which must report a time in ns; gives up after `limit`.
    fn in_child_with_limit(limit: Duration, f: impl FnOnce() -> f64) -> Option<f64> {
        let mut fds = [0 as c_int; 2];
        // SAFETY: `fds` has room for two descriptors.
        assert_eq!(unsafe { libc::pipe(fds.as_mut_ptr()) }, 0);
        // SAFETY: the benchmark is single-threaded; the child only computes, writes and exits.
        let pid = unsafe { libc::fork() };
        assert!(pid >= 0);
        if pid == 0 {
            let ns = f();
            // SAFETY: writing 8 bytes from a local to the pipe, then leaving without unwinding.
            unsafe {
                libc::write(fds[1], (&ns as *const f64).cast(), 8);
                libc::_exit(0);
            }
        }
        // SAFETY: closing our copy of the write end.
        unsafe { libc::close(fds[1]) };
        let start = Instant::now();
        let mut status = 0;
        loop {
            // SAFETY: waiting for our own child.
            if unsafe { libc::waitpid(pid, &mut status, libc::WNOHANG) } == pid {
                break;
            }
            if start.elapsed() > limit {
                // SAFETY: killing and reaping our own child.
                unsafe {
                    libc::kill(pid, libc::SIGKILL);
                    libc::waitpid(pid, &mut status, 0);
                    libc::close(fds[0]);
                }
                return None;
            }
            std::thread::sleep(Duration::from_millis(1));
        }
        let mut ns = 0f64;
        // SAFETY: reading 8 bytes into a local.
        let n = unsafe { libc::read(fds[0], (&mut ns as *mut f64).cast(), 8) };
        // SAFETY: closing our read end.
        unsafe { libc::close(fds[0]) };
        (n == 8).then_some(ns)
    }

    struct Compiled(*mut OpcPattern);

    impl Compiled {
        fn new(p: &[u16], cs: bool) -> Compiled {
            let mut f = ptr::null_mut();
            // SAFETY: NUL-terminated pattern, valid out-pointer.
            assert_eq!(unsafe { OpcPatternCompileW(p.as_ptr(), cs as i32, &mut f) }, 0);
            Compiled(f)
        }
        fn matches(&self, s: &[u16]) -> bool {
            // SAFETY: live filter, NUL-terminated string.
            unsafe { OpcPatternMatchW(self.0, s.as_ptr()) == 1 }
        }
    }

    impl Drop for Compiled {
        fn drop(&mut self) {
            // SAFETY: freed once.
            unsafe { OpcPatternFree(self.0) };
        }
    }

    fn ours_w(s: &[u16], p: &[u16], cs: bool) -> bool {
        // SAFETY: NUL-terminated strings.
        unsafe { MatchPatternW(s.as_ptr(), p.as_ptr(), cs as i32) == 1 }
    }

    fn ours_a(s: &CString, p: &CString, cs: bool) -> bool {
        // SAFETY: NUL-terminated strings.
        unsafe { MatchPatternA(s.as_ptr(), p.as_ptr(), cs as i32) == 1 }
    }

    fn fnmatch(s: &CString, p: &CString, flags: c_int) -> bool {
        // SAFETY: NUL-terminated strings.
        unsafe { libc::fnmatch(p.as_ptr(), s.as_ptr(), flags) == 0 }
    }

    // ---- Report ----

    struct Row {
        case: String,
        baseline: Result<f64, f64>,
        w: f64,
        compiled: f64,
        a: f64,
        fnmatch: Option<f64>,
    }

    fn fmt_ns(ns: f64) -> String {
        if ns >= 1e6 {
            format!("{:.1} ms", ns / 1e6)
        } else if ns >= 1e3 {
            format!("{:.2} us", ns / 1e3)
        } else {
            format!("{ns:.1} ns")
        }
    }

    fn fmt_baseline(b: &Result<f64, f64>) -> String {
        match b {
            Ok(ns) => fmt_ns(*ns),
            Err(ns) => format!(">= {} (budget)", fmt_ns(*ns)),
        }
    }

    fn fmt_ratio(r: f64, at_least: bool) -> String {
        if at_least {
            format!(">= {r:.1}x")
        } else {
            format!("{r:.1}x")
        }
    }

    fn print_rows(title: &str, unit: &str, rows: &[Row]) {
        println!("\n{title} ({unit})");
        println!(
            "{:<40} {:>22} {:>11} {:>11} {:>11} {:>13} {:>11} {:>11} {:>9}",
            "case", "baseline", "ours W", "compiled", "ours A", "fnmatch", "base/W", "base/comp", "fnm/W"
        );
        for r in rows {
            let (b, cut) = match r.baseline {
                Ok(x) => (x, false),
                Err(x) => (x, true),
            };
            println!(
                "{:<40} {:>22} {:>11} {:>11} {:>11} {:>13} {:>11} {:>11} {:>9}",
                r.case,
                fmt_baseline(&r.baseline),
                fmt_ns(r.w),
                fmt_ns(r.compiled),
                fmt_ns(r.a),
                r.fnmatch.map(fmt_ns).unwrap_or_else(|| "> 2 s (cut)".into()),
                fmt_ratio(b / r.w, cut),
                fmt_ratio(b / r.compiled, cut),
                r.fnmatch
                    .map(|f| format!("{:.1}x", f / r.w))
                    .unwrap_or_else(|| "-".into()),
            );
        }
    }

    /// One string against one pattern, every contender.
    fn single_case(case: String, s: &str, p: &str, cs: bool, expected: bool) -> Row {
        let (sw, pw) = (wide(s), wide(p));
        let (sa, pa) = (CString::new(s).unwrap(), CString::new(p).unwrap());
        let (sf, pf) = (CString::new(s).unwrap(), to_fnmatch(p));
        assert_eq!(ours_w(&sw, &pw, cs), expected, "{case}");
        assert_eq!(ours_a(&sa, &pa, cs), expected, "{case}");
        let compiled = Compiled::new(&pw, cs);
        assert_eq!(compiled.matches(&sw), expected, "{case}");
        let min = Duration::from_millis(30);
        let (mut w, mut c, mut a) = (f64::MAX, f64::MAX, f64::MAX);
        for _ in 0..ROUNDS {
            w = w.min(time_per_call(1, min, || {
                black_box(ours_w(black_box(&sw), black_box(&pw), cs));
            }));
            c = c.min(time_per_call(1, min, || {
                black_box(compiled.matches(black_box(&sw)));
            }));
            a = a.min(time_per_call(1, min, || {
                black_box(ours_a(black_box(&sa), black_box(&pa), cs));
            }));
        }
        let flags = fnmatch_flags(cs);
        let fnm = in_child_with_limit(Duration::from_secs(2), || {
            assert_eq!(fnmatch(&sf, &pf, flags), expected, "fnmatch disagrees: {case}");
            let start = Instant::now();
            let mut best = f64::MAX;
            for _ in 0..ROUNDS {
                best = best.min(time_per_call(1, min, || {
                    black_box(fnmatch(black_box(&sf), black_box(&pf), flags));
                }));
                if start.elapsed() > Duration::from_secs(1) {
                    break;
                }
            }
            best
        });
        let baseline = time_baseline(&sw, &pw, cs, expected);
        Row {
            case,
            baseline,
            w,
            compiled: c,
            a,
            fnmatch: fnm,
        }
    }

    pub fn run() {
        // `cargo bench --bench match_pattern -- typical` runs one set (adversarial, typical, worst);
        // `-- typical Device` only the typical filters containing "Device".
        let mut words = std::env::args().skip(1).filter(|a| !a.starts_with('-'));
        let only = words.next();
        // A second word keeps only the typical filters containing it.
        let filter = words.next();
        let wanted = |set: &str| only.is_none() || only.as_deref() == Some(set);
        println!("MatchPattern benchmark: baseline = the specification's Appendix B sample (recursive),");
        println!("ported for this benchmark, cut off after {BUDGET} recursive calls; ratios > 1 mean ours is faster.");

        // Adversarial set.
        let mut adversarial = Vec::new();
        let a100 = "a".repeat(100);
        for k in (4..=12).filter(|_| wanted("adversarial")) {
            let p = "a*".repeat(k) + "b";
            adversarial.push(single_case(format!("(a*)^{k} b vs 100 a"), &a100, &p, true, false));
        }
        let p = "*".repeat(12) + "b";
        if wanted("adversarial") {
            adversarial.push(single_case(
                "12 * then b vs 24 a".into(),
                &"a".repeat(24),
                &p,
                true,
                false,
            ));
        }
        print_rows("Adversarial set", "time per call", &adversarial);

        // Typical set.
        let mut ids = Vec::new();
        for c in 1..=10 {
            for d in 1..=10 {
                for t in 1..=1000 {
                    ids.push(format!("Channel{c}.Device{d}.Tag{t}"));
                }
            }
        }
        let ids_w: Vec<Vec<u16>> = ids.iter().map(|s| wide(s)).collect();
        let ids_a: Vec<CString> = ids.iter().map(|s| CString::new(s.as_str()).unwrap()).collect();
        let patterns = [
            "*Device1.Tag1#*",
            "Channel1.*",
            "*.Tag12?",
            "Channel?.Device[1-3].Tag*",
            "*[!0-9]",
            "*",
            "*Tag999",
            "*e*e*e*9",
        ];
        let mut typical = Vec::new();
        let mut totals = [0f64; 5];
        for cs in [true, false].into_iter().filter(|_| wanted("typical")) {
            for p in patterns {
                if filter.as_deref().is_some_and(|f| !p.contains(f)) {
                    continue;
                }
                let pw = wide(p);
                let pa = CString::new(p).unwrap();
                let pf = to_fnmatch(p);
                let flags = fnmatch_flags(cs);
                let n = ids.len();
                let compiled = Compiled::new(&pw, cs);
                // Every contender must select the same items.
                let count = |f: &dyn Fn(usize) -> bool| (0..n).filter(|&i| f(i)).count();
                let expected = count(&|i| ours_w(&ids_w[i], &pw, cs));
                assert_eq!(count(&|i| compiled.matches(&ids_w[i])), expected);
                assert_eq!(count(&|i| ours_a(&ids_a[i], &pa, cs)), expected);
                assert_eq!(count(&|i| fnmatch(&ids_a[i], &pf, flags)), expected, "fnmatch {p}");
                // SAFETY: NUL-terminated strings; well-formed pattern.
                let base_count =
                    count(&|i| unsafe { baseline(ids_w[i].as_ptr(), pw.as_ptr(), cs, &mut Budget(u64::MAX)) }.unwrap());
                assert_eq!(base_count, expected, "baseline {p}");

                // The machine may be shared: the contenders take turns, ROUNDS times, and each keeps
                // its best round, so a busy moment does not land on one contender only.
                let min = Duration::from_millis(40);
                let mut best = [f64::MAX; 5];
                for _ in 0..ROUNDS {
                    let times = [
                        time_per_call(n, min, || {
                            for s in &ids_w {
                                let mut budget = Budget(BUDGET);
                                // SAFETY: as above.
                                black_box(unsafe { baseline(s.as_ptr(), black_box(pw.as_ptr()), cs, &mut budget) });
                            }
                        }),
                        time_per_call(n, min, || {
                            for s in &ids_w {
                                black_box(ours_w(s, black_box(&pw), cs));
                            }
                        }),
                        time_per_call(n, min, || {
                            for s in &ids_w {
                                black_box(compiled.matches(s));
                            }
                        }),
                        time_per_call(n, min, || {
                            for s in &ids_a {
                                black_box(ours_a(s, black_box(&pa), cs));
                            }
                        }),
                        time_per_call(n, min, || {
                            for s in &ids_a {
                                black_box(fnmatch(s, black_box(&pf), flags));
                            }
                        }),
                    ];
                    for (b, t) in best.iter_mut().zip(times) {
                        *b = b.min(t);
                    }
                }
                let [b, w, c, a, f] = best;
                for (t, x) in totals.iter_mut().zip([b, w, c, a, f]) {
                    *t += x;
                }
                let mode = if cs { "cs" } else { "ci" };
                typical.push(Row {
                    case: format!("{p} [{mode}] ({expected} hits)"),
                    baseline: Ok(b),
                    w,
                    compiled: c,
                    a,
                    fnmatch: Some(f),
                });
            }
        }
        let [b, w, c, a, f] = totals;
        typical.push(Row {
            case: "whole typical set (sum)".into(),
            baseline: Ok(b),
            w,
            compiled: c,
            a,
            fnmatch: Some(f),
        });
        print_rows(
            "Typical set: 100,000 item IDs Channel{1..10}.Device{1..10}.Tag{1..1000}",
            "time per item",
            &typical,
        );

        // Worst case for our algorithm: 4 KiB patterns against 4 KiB strings.
        let mut worst = Vec::new();
        // Each pattern is 4 KiB of UTF-16 (4096 units, trailing `*`s as padding), each string 4096 `a`.
        // A middle segment that matches everywhere except at its last token forces the search to try
        // it at every place: about len(string) x len(segment) / 4 token steps.
        let pad = |p: String| {
            let n = p.encode_utf16().count();
            p + &"*".repeat(4096usize.saturating_sub(n))
        };
        let a4096 = "a".repeat(4096);
        let cases: [(&str, String, bool); 5] = [
            (
                "*?{2046}#* vs a{4096} [cs]",
                pad("*".to_string() + &"?".repeat(2046) + "#"),
                true,
            ),
            (
                "*(a?){1023}#* vs a{4096} [cs]",
                pad("*".to_string() + &"a?".repeat(1023) + "#"),
                true,
            ),
            (
                "*[a-z]{818}#* vs a{4096} [ci]",
                pad("*".to_string() + &"[a-z]".repeat(818) + "#"),
                false,
            ),
            (
                "*a{2046}#* vs a{4096} [ci]",
                pad("*".to_string() + &"a".repeat(2046) + "#"),
                false,
            ),
            ("(*?){2047}b vs a{4096} [cs]", "*?".repeat(2047) + "b", true),
        ];
        for (name, p, cs) in cases.into_iter().filter(|_| wanted("worst")) {
            assert!(p.encode_utf16().count() >= 4095);
            worst.push(single_case(name.into(), &a4096, &p, cs, false));
        }
        print_rows("Worst case: 4 KiB pattern vs 4 KiB string", "time per call", &worst);

        // Goals.
        if only.is_some() {
            return;
        }
        let max_adv = adversarial.iter().map(|r| r.w.max(r.compiled)).fold(0.0, f64::max);
        println!("\nGoals");
        println!(
            "- adversarial <= 2 us per call at every k: {} (slowest: {})",
            if max_adv <= 2000.0 { "met" } else { "NOT met" },
            fmt_ns(max_adv)
        );
        let ratio_rows = &typical[..typical.len() - 1];
        let base = |r: &Row| r.baseline.unwrap_or_else(|x| x);
        let min_w = ratio_rows.iter().map(|r| base(r) / r.w).fold(f64::MAX, f64::min);
        let min_c = ratio_rows.iter().map(|r| base(r) / r.compiled).fold(f64::MAX, f64::min);
        let min_f = ratio_rows
            .iter()
            .map(|r| r.fnmatch.unwrap() / r.w)
            .fold(f64::MAX, f64::min);
        println!(
            "- typical, MatchPatternW >= 3x baseline: whole set {:.1}x ({}), worst single pattern {:.1}x ({})",
            b / w,
            if b / w >= 3.0 { "met" } else { "NOT met" },
            min_w,
            if min_w >= 3.0 { "met" } else { "NOT met" }
        );
        println!(
            "- typical, compiled filter >= 5x baseline: whole set {:.1}x ({}), worst single pattern {:.1}x ({})",
            b / c,
            if b / c >= 5.0 { "met" } else { "NOT met" },
            min_c,
            if min_c >= 5.0 { "met" } else { "NOT met" }
        );
        println!(
            "- typical, MatchPatternW as fast as fnmatch: whole set {:.1}x ({}), worst single pattern {:.1}x ({})",
            f / w,
            if f / w >= 1.0 { "met" } else { "NOT met" },
            min_f,
            if min_f >= 1.0 { "met" } else { "NOT met" }
        );
        let max_worst = worst.iter().map(|r| r.w.max(r.compiled)).fold(0.0, f64::max);
        println!(
            "- worst case <= 50 ms: {} (slowest: {})",
            if max_worst <= 50e6 { "met" } else { "NOT met" },
            fmt_ns(max_worst)
        );
    }
}
