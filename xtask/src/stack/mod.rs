//! `cargo xtask stack`: the static worst-case stack bound of the `pfe-qemu` firmware.
//!
//! Builds `pfe-qemu` as shipped (release, opt-level s) with `-Z emit-stack-sizes` into
//! `target/stack`, reads each function's frame from `llvm-readobj --stack-sizes` and the call
//! edges from `llvm-objdump -d`, and walks the call graph for the costliest path:
//!
//! - edges: `bl`, and `b`/`b<cond>`/`cbz`/`cbnz` into another function (tail calls);
//! - a function without a `.stack_sizes` entry (precompiled `compiler_builtins`, a few that
//!   lost theirs in LTO, hand-written assembly) gets the sum of every stack decrement in its
//!   body: `push` (4 B per register), `vpush` (4 per s-, 8 per d-register),
//!   `str rN, [sp, #-n]!`, `sub sp, #imm` (the prologue in practice; a sum over every path is an
//!   upper bound);
//! - indirect calls with one known target ([`INDIRECT`]): an edge to it;
//! - errors, because the bound would not be sound: any other indirect call or jump (`blx rN`,
//!   `bx rN` other than `bx lr`, a load or move into `pc` that is not a return), a stack
//!   adjusted by a register amount in a function without an entry, a branch into the middle
//!   of another function, and a cycle (recursion), all only when reachable from a root;
//! - exceptions on top of `main`'s path: the device interrupts and SysTick share one
//!   priority (the firmware sets none, so all are 0 and none preempts another): the costlier
//!   of their paths, plus the exception frame (104 B with the FPU context, + 4 B of alignment
//!   the core may insert); then a HardFault (priority -1) on top, with its frame too.
//!
//! Writes the "Static worst-case stack bound" section of docs/PERFORMANCE.md.
//! `cargo xtask size` calls [`refresh`] to print the bound beside the painted high-water mark.

use std::collections::{BTreeMap, HashMap};
use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::process::Command;

use anyhow::{bail, Context, Result};

use crate::fw::{target_dir, write_section_titled, FIRMWARE_OPT_LEVEL};
use crate::util;

const TARGET: &str = "thumbv7em-none-eabihf";
const BIN: &str = "pfe-qemu";
/// Where `main`'s path starts (cortex-m-rt's `Reset` calls it with an empty stack).
const MAIN: &str = "main";
/// Handlers at the one priority every exception and interrupt of the firmware has (none is
/// set): SysTick and the device interrupts (`DefaultHandler`, UART0's receive interrupt).
const SAME_PRIORITY: [&str; 2] = ["SysTick", "DefaultHandler"];
/// cortex-m-rt's HardFault entry (the trampoline that calls the user's handler).
const HARD_FAULT: &str = "HardFault";
/// Exception frame of a Cortex-M4F with the FPU context stacked: r0-r3, r12, lr, pc, xPSR,
/// s0-s15, FPSCR and a reserved word (26 words).
pub const EXCEPTION_FRAME: u64 = 104;
/// With CCR.STKALIGN (reset value 1 on the Cortex-M4) the core aligns the frame to 8 bytes,
/// inserting 4 bytes when `sp` was only 4-aligned (between two pushes of a prologue).
pub const FRAME_ALIGNMENT: u64 = 4;

/// Indirect calls whose target is known, by demangled name: (a suffix of the caller, the one
/// function its `blx` may reach). pfe-core's `FeatureSink::retain` takes a `&mut dyn FnMut`,
/// and its one caller, the sift (`pfe_core::sift::sift`, with the checks for real scans),
/// passes its one closure (`cargo xtask stack` fails if the callee is not in the binary, and a
/// second caller with another closure would be a change to pfe-core that must extend this
/// table). Every `blx` in the caller is taken to call the callee.
const INDIRECT: [(&str, &str); 1] = [(
    " as pfe_core::output::FeatureSink>::retain",
    "pfe_core::sift::sift::{closure#0}",
)];

mod parse;
#[cfg(test)]
mod tests;

use parse::{is_op, jump_table_within, loads_pc_indirectly, stack_decrement, target};
pub use parse::{parse_disassembly, parse_stack_sizes, parse_symbols, Function};

/// How a function's frame was found.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Source {
    /// Its `.stack_sizes` entry.
    StackSizes,
    /// The stack decrements of its code (no entry).
    Prologue,
}

/// How a function reaches a callee.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Edge {
    Call,
    TailCall,
}

/// A function of the call graph.
#[derive(Debug, Clone)]
pub struct Node {
    pub name: String,
    pub addr: u32,
    pub frame: u64,
    pub source: Source,
    /// Callees (node indices), each once, in code order.
    pub callees: Vec<(usize, Edge)>,
    /// Why a bound through this function would not be sound (reported when reachable).
    pub problems: Vec<String>,
}

/// The call graph of a binary.
#[derive(Debug, Clone)]
pub struct Graph {
    pub nodes: Vec<Node>,
    /// Every function symbol's address (objdump names one symbol per address).
    pub symbols: HashMap<String, u32>,
}

/// Builds the call graph from the functions, their symbols' addresses and the stack-size
/// entries.
pub fn build(
    functions: &[Function],
    symbols: &HashMap<String, u32>,
    sizes: &[(Vec<String>, u64)],
) -> Graph {
    let mut frame_at: HashMap<u32, u64> = HashMap::new();
    for (names, size) in sizes {
        if let Some(addr) = names.iter().find_map(|n| symbols.get(n)) {
            frame_at.insert(*addr, *size);
        }
    }
    let starts: BTreeMap<u32, usize> = functions
        .iter()
        .enumerate()
        .map(|(k, f)| (f.addr, k))
        .collect();
    // The function holding `addr` (the last one starting at or before it).
    let holder = |addr: u32| starts.range(..=addr).next_back().map(|(a, k)| (*a, *k));
    let mut nodes = Vec::with_capacity(functions.len());
    for (me, f) in functions.iter().enumerate() {
        let end = functions.get(me + 1).map_or(u32::MAX, |n| n.addr);
        let mut callees: Vec<(usize, Edge)> = Vec::new();
        let mut problems = Vec::new();
        let mut decrement = 0u64;
        for i in &f.insns {
            let m = i.mnemonic.as_str();
            let shown = || format!("{:x}: `{} {}`", i.addr, i.mnemonic, i.operands);
            let first_op = i.operands.split([',', ' ']).next().unwrap_or("");
            if is_op(m, "blx") {
                let known = INDIRECT
                    .iter()
                    .find(|(caller, _)| f.name.ends_with(caller))
                    .and_then(|(_, callee)| functions.iter().position(|g| g.name == *callee));
                match known {
                    Some(k) => {
                        if !callees.iter().any(|(c, _)| *c == k) {
                            callees.push((k, Edge::Call));
                        }
                    }
                    None => problems.push(format!("indirect call {}", shown())),
                }
            } else if is_op(m, "bx") {
                if first_op != "lr" {
                    problems.push(format!("indirect jump {}", shown()));
                }
            } else if is_op(m, "bl") || is_op(m, "b") || is_op(m, "cbz") || is_op(m, "cbnz") {
                let Some(t) = target(&i.operands) else {
                    problems.push(format!("branch without a target address {}", shown()));
                    continue;
                };
                let call = is_op(m, "bl");
                if !call && (f.addr..end).contains(&t) {
                    continue; // within the function
                }
                match holder(t) {
                    Some((start, k)) if start == t => {
                        let edge = if call { Edge::Call } else { Edge::TailCall };
                        if !callees.iter().any(|(c, _)| *c == k) {
                            callees.push((k, edge));
                        }
                    }
                    Some((start, k)) => problems.push(format!(
                        "branch into {} at +{:#x} {}",
                        functions.get(k).map_or("?", |g| g.name.as_str()),
                        t - start,
                        shown()
                    )),
                    None => problems.push(format!("branch outside every function {}", shown())),
                }
            } else if loads_pc_indirectly(i) {
                // A jump table the compiler laid out in this function (`adr rN, #t` / `add rN,
                // rN, rM, lsl #2` / `mov pc, rN`: a branch per entry, inside the function) moves
                // no stack and calls nothing the scan of its instructions does not see.
                if !jump_table_within(&f.insns, i, end) {
                    problems.push(format!("indirect jump {}", shown()));
                }
            }
            if !frame_at.contains_key(&f.addr) {
                match stack_decrement(i) {
                    Ok(n) => decrement += n,
                    Err(e) => problems.push(format!("{e} at {:x}", i.addr)),
                }
            }
        }
        let (frame, source) = match frame_at.get(&f.addr) {
            Some(s) => (*s, Source::StackSizes),
            None => (decrement, Source::Prologue),
        };
        nodes.push(Node {
            name: f.name.clone(),
            addr: f.addr,
            frame,
            source,
            callees,
            problems,
        });
    }
    Graph {
        nodes,
        symbols: symbols.clone(),
    }
}

/// One function of a worst path: its node and how its caller reached it.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Step {
    pub node: usize,
    pub edge: Option<Edge>,
}

/// The costliest path from a root.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct WorstPath {
    /// The name the walk started from (it may be an alias of the first step's function).
    pub root: String,
    pub steps: Vec<Step>,
    pub total: u64,
}

impl Graph {
    /// The node named `name`.
    /// The node named `name`, or at the address of the symbol `name` (an alias).
    pub fn find(&self, name: &str) -> Result<usize> {
        let addr = self.symbols.get(name);
        self.nodes
            .iter()
            .position(|n| n.name == name || Some(&n.addr) == addr)
            .with_context(|| format!("no function `{name}` in the disassembly"))
    }

    /// The costliest path from the function (or alias) `name`.
    pub fn worst_from(&self, name: &str) -> Result<WorstPath> {
        let mut p = self.worst(self.find(name)?)?;
        p.root = name.to_string();
        Ok(p)
    }

    /// The costliest path from `root`; an error for a cycle or a problem on any reachable
    /// function.
    pub fn worst(&self, root: usize) -> Result<WorstPath> {
        #[derive(Clone, Copy, PartialEq)]
        enum State {
            New,
            Open,
            Done,
        }
        struct Walk<'a> {
            g: &'a Graph,
            state: Vec<State>,
            /// Costliest total from a node, and the callee it goes through.
            best: Vec<(u64, Option<(usize, Edge)>)>,
            stack: Vec<usize>,
        }
        impl Walk<'_> {
            fn visit(&mut self, n: usize) -> Result<u64> {
                match self.state.get(n) {
                    Some(State::Done) => return Ok(self.best.get(n).map_or(0, |b| b.0)),
                    Some(State::Open) => {
                        let from = self.stack.iter().position(|s| *s == n).unwrap_or(0);
                        let cycle: Vec<&str> = self
                            .stack
                            .get(from..)
                            .unwrap_or(&[])
                            .iter()
                            .chain([&n])
                            .map(|k| self.g.name(*k))
                            .collect();
                        bail!("recursion, no static bound: cycle {}", cycle.join(" -> "));
                    }
                    _ => {}
                }
                let node = self.g.nodes.get(n).context("node index")?;
                if let Some(p) = node.problems.first() {
                    let path: Vec<&str> = self
                        .stack
                        .iter()
                        .chain([&n])
                        .map(|k| self.g.name(*k))
                        .collect();
                    bail!(
                        "no sound static bound: {p} in `{}` (reached by {})",
                        node.name,
                        path.join(" -> ")
                    );
                }
                if let Some(s) = self.state.get_mut(n) {
                    *s = State::Open;
                }
                self.stack.push(n);
                let mut best: (u64, Option<(usize, Edge)>) = (node.frame, None);
                for &(c, e) in &node.callees {
                    let t = node.frame + self.visit(c)?;
                    if t > best.0 {
                        best = (t, Some((c, e)));
                    }
                }
                self.stack.pop();
                if let (Some(s), Some(b)) = (self.state.get_mut(n), self.best.get_mut(n)) {
                    *s = State::Done;
                    *b = best;
                }
                Ok(best.0)
            }
        }
        let mut w = Walk {
            g: self,
            state: vec![State::New; self.nodes.len()],
            best: vec![(0, None); self.nodes.len()],
            stack: Vec::new(),
        };
        let total = w.visit(root)?;
        let mut steps = vec![Step {
            node: root,
            edge: None,
        }];
        let mut at = root;
        while let Some((c, e)) = w.best.get(at).and_then(|b| b.1) {
            steps.push(Step {
                node: c,
                edge: Some(e),
            });
            at = c;
        }
        Ok(WorstPath {
            root: self.name(root).to_string(),
            steps,
            total,
        })
    }

    fn name(&self, n: usize) -> &str {
        self.nodes.get(n).map_or("?", |x| x.name.as_str())
    }
}

/// The bound: `main`'s path, the costliest handler at the shared priority, the HardFault.
#[derive(Debug, Clone)]
pub struct Bound {
    pub graph: Graph,
    pub main: WorstPath,
    pub handler: WorstPath,
    /// Each handler at the shared priority: name and path total.
    pub handlers: Vec<(String, u64)>,
    pub hard_fault: WorstPath,
}

impl Bound {
    /// Computes the three paths.
    pub fn of(graph: Graph) -> Result<Bound> {
        let main = graph.worst_from(MAIN)?;
        let mut handler: Option<WorstPath> = None;
        let mut handlers = Vec::new();
        for h in SAME_PRIORITY {
            let p = graph.worst_from(h)?;
            handlers.push((h.to_string(), p.total));
            if handler.as_ref().is_none_or(|b| p.total > b.total) {
                handler = Some(p);
            }
        }
        let handler = handler.context("no interrupt handler")?;
        let hard_fault = graph.worst_from(HARD_FAULT)?;
        Ok(Bound {
            graph,
            main,
            handler,
            handlers,
            hard_fault,
        })
    }

    /// Bytes an exception adds: its handler's path and its frame.
    fn exception(p: &WorstPath) -> u64 {
        p.total + EXCEPTION_FRAME + FRAME_ALIGNMENT
    }

    /// `main`'s path plus the handler at the shared priority.
    pub fn with_interrupt(&self) -> u64 {
        self.main.total + Self::exception(&self.handler)
    }

    /// The bound: with a HardFault on top.
    pub fn total(&self) -> u64 {
        self.with_interrupt() + Self::exception(&self.hard_fault)
    }

    fn node(&self, s: &Step) -> Option<&Node> {
        self.graph.nodes.get(s.node)
    }

    /// A path as terminal lines: frame, source, name.
    fn lines(&self, p: &WorstPath, out: &mut String) {
        for (k, s) in p.steps.iter().enumerate() {
            let Some(n) = self.node(s) else { continue };
            let how = match s.edge {
                Some(Edge::TailCall) => "tail call ",
                _ => "",
            };
            let src = match n.source {
                Source::StackSizes => "",
                Source::Prologue => " (frame from the prologue)",
            };
            let name = Self::shown(p, k, n);
            let _ = writeln!(out, "  {:>6}  {how}{name} @ {:#x}{src}", n.frame, n.addr);
        }
    }

    /// The terminal report.
    pub fn text(&self) -> String {
        let mut s = String::from("main path:\n");
        self.lines(&self.main, &mut s);
        let _ = writeln!(s, "  {:>6}  main path total", self.main.total);
        let hname = self.handler_name();
        let _ = writeln!(
            s,
            "\ninterrupt (one priority, none preempts another: {}; costliest: {hname}):",
            self.handler_totals()
        );
        self.lines(&self.handler, &mut s);
        let _ = writeln!(
            s,
            "  {:>6}  exception frame: {EXCEPTION_FRAME} (FPU context) + {FRAME_ALIGNMENT} (alignment)",
            EXCEPTION_FRAME + FRAME_ALIGNMENT
        );
        let _ = writeln!(s, "  {:>6}  with {hname}", self.with_interrupt());
        s.push_str("\nHardFault on top:\n");
        self.lines(&self.hard_fault, &mut s);
        let _ = writeln!(
            s,
            "  {:>6}  exception frame: {EXCEPTION_FRAME} (FPU context) + {FRAME_ALIGNMENT} (alignment)",
            EXCEPTION_FRAME + FRAME_ALIGNMENT
        );
        let _ = writeln!(s, "  {:>6}  static worst-case stack bound", self.total());
        s
    }

    /// `SysTick 8 B, DefaultHandler 40 B`.
    fn handler_totals(&self) -> String {
        self.handlers
            .iter()
            .map(|(n, t)| format!("{n} {t} B"))
            .collect::<Vec<_>>()
            .join(", ")
    }

    fn handler_name(&self) -> &str {
        &self.handler.root
    }

    /// The name a step is shown with: the root's own for the first.
    fn shown<'a>(p: &'a WorstPath, k: usize, n: &'a Node) -> &'a str {
        if k == 0 {
            &p.root
        } else {
            &n.name
        }
    }

    /// A path as one Markdown cell: `a` (frame) → `b` (frame) ….
    fn cell(&self, p: &WorstPath) -> String {
        p.steps
            .iter()
            .enumerate()
            .filter_map(|(k, s)| {
                let n = self.node(s)?;
                let tail = if s.edge == Some(Edge::TailCall) {
                    ", tail call"
                } else {
                    ""
                };
                let src = if n.source == Source::Prologue {
                    ", prologue"
                } else {
                    ""
                };
                let name = short(Self::shown(p, k, n));
                Some(format!("`{name}` ({}{src}{tail})", n.frame))
            })
            .collect::<Vec<_>>()
            .join(" → ")
    }

    /// The docs section (without the heading).
    pub fn markdown(&self, elf_note: &str) -> String {
        let hname = self.handler_name();
        format!(
            "Static worst-case stack bound of the `pfe-qemu` firmware ({elf_note}), the binary \
             whose painted high-water mark `cargo xtask size` measures (table above; `cargo \
             xtask size` prints both).\n\n\
             ```sh\n\
             RUSTC_BOOTSTRAP=1 RUSTFLAGS=\"-Z emit-stack-sizes -C linker=flip-link\" \\\n  \
             CARGO_PROFILE_RELEASE_OPT_LEVEL={FIRMWARE_OPT_LEVEL} CARGO_TARGET_DIR=target/stack \\\n  \
             cargo build --release -p firmware-qemu --bin {BIN} --target {TARGET}\n\
             llvm-readobj --stack-sizes …/{BIN}   # frame per function\n\
             llvm-objdump -t …/{BIN}              # symbol addresses (aliases)\n\
             llvm-objdump -d -C …/{BIN}           # call edges\n\
             ```\n\n\
             Walk: call edges are the `bl` instructions and the `b`/`b<cond>`/`cbz`/`cbnz` \
             branches into another function (tail calls); the bound is the costliest path \
             (frame sizes summed). A function without a `.stack_sizes` entry (the precompiled \
             `compiler_builtins`, functions whose entry did not survive LTO, cortex-m-rt's \
             assembly) gets the sum of the stack decrements in its code (`push`, `vpush`, \
             `str rN, [sp, #-n]!`, `sub sp, #imm`): marked *prologue* below. The command fails \
             on anything that would make the bound unsound when it is reachable: an indirect \
             call or jump (`blx rN`, `bx rN`), `sp` adjusted by a register, a branch into the \
             middle of a function, a cycle (recursion). None is reachable here. \
             Exceptions: the firmware sets no priority, so SysTick and the device interrupts \
             (`DefaultHandler`, UART0's receive interrupt) share priority 0 and do not preempt \
             one another: the costlier of the two is stacked on `main`'s path, then a \
             HardFault (priority -1), each with its exception frame ({EXCEPTION_FRAME} B with \
             the FPU context, + {FRAME_ALIGNMENT} B the core may insert to align it to 8).\n\n\
             | path | bytes |\n|---|---:|\n\
             | {} | **{}** |\n\
             | + {hname} (the costliest at priority 0: {}): {} + exception frame {EXCEPTION_FRAME} + {FRAME_ALIGNMENT} | {} |\n\
             | + HardFault on top: {} + exception frame {EXCEPTION_FRAME} + {FRAME_ALIGNMENT} | **{}** |\n{}",
            self.cell(&self.main),
            self.main.total,
            self.handler_totals(),
            self.cell(&self.handler),
            self.with_interrupt(),
            self.cell(&self.hard_fault),
            self.total(),
            self.notes(),
        )
    }

    /// Remarks on the main path's costliest known frames.
    fn notes(&self) -> String {
        let on_path = |what: &str| {
            self.main.steps.iter().find_map(|s| {
                let n = self.node(s)?;
                n.name.contains(what).then_some(n.frame)
            })
        };
        let mut s = String::new();
        if let Some(frame) = on_path("rem_pio2f") {
            let _ = write!(
                s,
                "\nThe {frame} B of libm's `rem_pio2f` are its large-argument reduction, which \
                 runs only for |x| ≥ 2^28·π/2, an angle no scan produces: one reason the painted \
                 high-water mark stays below the bound.\n"
            );
        }
        s
    }
}

/// A short form of a demangled name for the docs: generic arguments and `<… as …>` dropped,
/// the last two path segments kept (`<lms2xx::driver::Driver<…>>::init` →
/// `Driver::init`).
pub fn short(name: &str) -> String {
    // Drop generic arguments: a `<` that follows an identifier character or `::`.
    let mut out = String::new();
    let mut depth = 0usize;
    let mut prev = ' ';
    for c in name.chars() {
        if depth > 0 {
            match c {
                '<' => depth += 1,
                '>' => depth -= 1,
                _ => {}
            }
            continue;
        }
        if c == '<' && (prev.is_alphanumeric() || prev == '_' || prev == ':') {
            depth = 1;
            continue;
        }
        out.push(c);
        prev = c;
    }
    let out = out.replace("::::", "::");
    let out = out.trim_end_matches("::");
    // `<A as B>::f` → `A::f`, `<A>::f` → `A::f`
    let out = match out.strip_prefix('<').and_then(|r| r.split_once(">::")) {
        Some((ty, f)) => format!("{}::{f}", ty.split(" as ").next().unwrap_or(ty)),
        None => out.to_string(),
    };
    let segs: Vec<&str> = out.split("::").collect();
    segs.get(segs.len().saturating_sub(2)..)
        .unwrap_or(&[])
        .join("::")
}

/// Runs `tool args elf`, returns its standard output.
fn output(tool: &Path, args: &[&str], elf: &Path) -> Result<String> {
    let out = Command::new(tool)
        .args(args)
        .arg(elf)
        .output()
        .with_context(|| format!("running {}", tool.display()))?;
    if !out.status.success() {
        bail!(
            "{} {args:?} failed: {}",
            tool.display(),
            String::from_utf8_lossy(&out.stderr)
        );
    }
    Ok(String::from_utf8_lossy(&out.stdout).into_owned())
}

/// Builds `pfe-qemu` with `-Z emit-stack-sizes` into `$CARGO_TARGET_DIR/stack`; the ELF.
pub fn build_elf() -> Result<PathBuf> {
    util::ensure_target()?;
    util::ensure_flip_link()?;
    let dir = target_dir().join("stack");
    let mut c = util::cargo();
    c.args(["build", "--release", "-p", "firmware-qemu", "--bin", BIN])
        .args(["--target", TARGET])
        .env("RUSTC_BOOTSTRAP", "1")
        .env("RUSTFLAGS", "-Z emit-stack-sizes -C linker=flip-link")
        .env_remove("CARGO_ENCODED_RUSTFLAGS")
        .env("CARGO_PROFILE_RELEASE_OPT_LEVEL", FIRMWARE_OPT_LEVEL)
        .env("CARGO_TARGET_DIR", &dir)
        .env("DEFMT_LOG", "info");
    util::run(&mut c)?;
    Ok(dir.join(TARGET).join("release").join(BIN))
}

/// The bound of `elf` (built with `-Z emit-stack-sizes`).
pub fn analyse(elf: &Path) -> Result<Bound> {
    let objdump = util::llvm_tool("llvm-objdump")?;
    let readobj = util::llvm_tool("llvm-readobj")?;
    let sizes = parse_stack_sizes(&output(&readobj, &["--stack-sizes"], elf)?)?;
    if sizes.is_empty() {
        bail!(
            "{} has no .stack_sizes entries (built without -Z emit-stack-sizes?)",
            elf.display()
        );
    }
    let symbols = parse_symbols(&output(&objdump, &["-t"], elf)?);
    let functions = parse_disassembly(&output(&objdump, &["-d", "-C"], elf)?)?;
    Bound::of(build(&functions, &symbols, &sizes))
}

/// Builds, analyses, prints the report and rewrites the docs section; the ELF and its bound.
pub fn refresh() -> Result<(PathBuf, Bound)> {
    let elf = build_elf()?;
    let bound = analyse(&elf)?;
    println!(
        "static worst-case stack bound of {}:\n\n{}",
        elf.display(),
        bound.text()
    );
    write_section_titled(
        &util::root().join("docs").join("PERFORMANCE.md"),
        "stack",
        "Static worst-case stack bound",
        "stack",
        &bound.markdown(&format!(
            "release, opt-level {FIRMWARE_OPT_LEVEL}, {TARGET}"
        )),
    )?;
    Ok((elf, bound))
}

/// Entry point: `cargo xtask stack [--functions]` (`--functions` also lists every function's
/// frame, its source and its callees).
pub fn run(args: &[String]) -> Result<()> {
    let functions = match args {
        [] => false,
        [f] if f == "--functions" => true,
        _ => bail!("usage: cargo xtask stack [--functions]"),
    };
    let (_, bound) = refresh()?;
    if functions {
        println!("\nevery function (frame, source, callees; ~ marks a tail call):");
        for n in &bound.graph.nodes {
            let callees: Vec<String> = n
                .callees
                .iter()
                .filter_map(|(c, e)| {
                    let c = bound.graph.nodes.get(*c)?;
                    let tail = if *e == Edge::TailCall { "~" } else { "" };
                    Some(format!("{tail}{}", short(&c.name)))
                })
                .collect();
            let src = match n.source {
                Source::StackSizes => "entry",
                Source::Prologue => "prologue",
            };
            println!(
                "  {:>6} {src:<8} {:#07x} {}{}{}",
                n.frame,
                n.addr,
                n.name,
                if callees.is_empty() { "" } else { " -> " },
                callees.join(", ")
            );
            for p in &n.problems {
                println!("         problem: {p}");
            }
        }
    }
    Ok(())
}
