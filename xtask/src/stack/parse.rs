//! Parsing of the LLVM tools' output: `llvm-objdump -d` (functions and instructions),
//! `llvm-objdump -t` (symbol addresses), `llvm-readobj --stack-sizes` (frames), and the
//! instruction facts the walk needs (mnemonic bases, branch targets, stack decrements).

use std::collections::HashMap;

use anyhow::{bail, Context, Result};

/// One instruction of `llvm-objdump -d`.
#[derive(Debug, Clone, PartialEq)]
pub struct Insn {
    pub addr: u32,
    /// Encoding as printed (`b580`, `f002 fc96`).
    pub bytes: String,
    pub mnemonic: String,
    pub operands: String,
}

/// A symbol's code as `llvm-objdump -d` prints it.
#[derive(Debug, Clone, PartialEq)]
pub struct Function {
    pub addr: u32,
    pub name: String,
    pub insns: Vec<Insn>,
}

/// Parses `llvm-objdump -d` output: functions (symbol headers `0000abcd <name>:`) and their
/// instructions.
pub fn parse_disassembly(text: &str) -> Result<Vec<Function>> {
    let mut out: Vec<Function> = Vec::new();
    for (n, line) in text.lines().enumerate() {
        let ctx = || format!("objdump line {}: {line:?}", n + 1);
        if let Some((addr, rest)) = line.split_once(" <") {
            if !addr.starts_with(' ') && !addr.is_empty() {
                if let (Ok(addr), Some(name)) =
                    (u32::from_str_radix(addr, 16), rest.strip_suffix(">:"))
                {
                    out.push(Function {
                        addr,
                        name: name.to_string(),
                        insns: Vec::new(),
                    });
                    continue;
                }
            }
        }
        let trimmed = line.trim_start();
        let Some((addr, rest)) = trimmed.split_once(':') else {
            continue;
        };
        if line.len() == trimmed.len() || addr.is_empty() {
            continue; // headers such as "Disassembly of section .text:"
        }
        let Ok(addr) = u32::from_str_radix(addr, 16) else {
            continue;
        };
        let mut fields = rest.split('\t');
        let bytes = fields.next().unwrap_or("").trim().to_string();
        let mnemonic = fields.next().unwrap_or("").trim().to_string();
        let operands = fields.collect::<Vec<_>>().join(" ").trim().to_string();
        let Some(f) = out.last_mut() else {
            bail!("instruction before any symbol: {}", ctx());
        };
        f.insns.push(Insn {
            addr,
            bytes,
            mnemonic,
            operands,
        });
    }
    // lld fills the gaps between functions with 0xd4d4 (a trap pattern that decodes as
    // `bmi`); objdump lists it under the function before the gap.
    for f in &mut out {
        while f.insns.last().is_some_and(|i| i.bytes == "d4d4") {
            f.insns.pop();
        }
    }
    Ok(out)
}

/// Parses `llvm-objdump -t`: every symbol name of a function (`F`) with its address.
pub fn parse_symbols(text: &str) -> HashMap<String, u32> {
    let mut out = HashMap::new();
    for line in text.lines() {
        let Some((left, right)) = line.split_once('\t') else {
            continue;
        };
        let mut l = left.split_whitespace();
        let Some(Ok(addr)) = l.next().map(|a| u32::from_str_radix(a, 16)) else {
            continue;
        };
        if !l.any(|flag| flag == "F") {
            continue;
        }
        // "<size> [.hidden ]<name>"
        let mut r = right.split_whitespace();
        let _size = r.next();
        let Some(name) = r.rfind(|w| *w != ".hidden") else {
            continue;
        };
        out.insert(name.to_string(), addr & !1);
    }
    out
}

/// Parses `llvm-readobj --stack-sizes`: each entry's function names (aliases) and frame size.
pub fn parse_stack_sizes(text: &str) -> Result<Vec<(Vec<String>, u64)>> {
    let mut out = Vec::new();
    let mut names: Option<Vec<String>> = None;
    for line in text.lines() {
        let line = line.trim();
        if let Some(list) = line.strip_prefix("Functions:") {
            let list = list.trim().trim_start_matches('[').trim_end_matches(']');
            names = Some(list.split(',').map(|s| s.trim().to_string()).collect());
        } else if let Some(size) = line.strip_prefix("Size:") {
            let Some(n) = names.take() else {
                bail!("readobj: a Size without Functions: {line:?}");
            };
            let size = size.trim();
            let value = match size.strip_prefix("0x") {
                Some(hex) => u64::from_str_radix(hex, 16),
                None => size.parse(),
            }
            .with_context(|| format!("readobj: size {size:?}"))?;
            out.push((n, value));
        }
    }
    Ok(out)
}

/// ARM condition codes (the suffixes of a conditional branch).
const CONDS: [&str; 16] = [
    "eq", "ne", "cs", "hs", "cc", "lo", "mi", "pl", "vs", "vc", "hi", "ls", "ge", "lt", "gt", "le",
];

/// `m` without a `.w`/`.n` width suffix.
pub(super) fn base(m: &str) -> &str {
    m.strip_suffix(".w")
        .or_else(|| m.strip_suffix(".n"))
        .unwrap_or(m)
}

/// `m` is `op` or `op<cond>` (`op` + condition code).
pub(super) fn is_op(m: &str, op: &str) -> bool {
    let m = base(m);
    m.strip_prefix(op)
        .is_some_and(|c| c.is_empty() || CONDS.contains(&c))
}

/// The first `0x…` number of a branch's operands (the target).
pub(super) fn target(operands: &str) -> Option<u32> {
    let hex = operands.split("0x").nth(1)?;
    let digits: String = hex.chars().take_while(char::is_ascii_hexdigit).collect();
    u32::from_str_radix(&digits, 16).ok()
}

/// `#12`, `#0x4`, `#-0x4` → the number.
pub(super) fn imm(s: &str) -> Option<i64> {
    let s = s.trim().strip_prefix('#')?;
    let (neg, s) = match s.strip_prefix('-') {
        Some(rest) => (true, rest),
        None => (false, s),
    };
    let v = match s.strip_prefix("0x") {
        Some(hex) => i64::from_str_radix(hex, 16).ok()?,
        None => s.parse().ok()?,
    };
    Some(if neg { -v } else { v })
}

/// Bytes of a register list `{r4, r5, lr}` / `{d8-d10}` / `{s16, s17}`.
pub(super) fn reg_list_bytes(operands: &str) -> Result<u64> {
    let inner = operands
        .split_once('{')
        .and_then(|(_, r)| r.split_once('}'))
        .map(|(l, _)| l)
        .with_context(|| format!("no register list in {operands:?}"))?;
    let mut total = 0;
    for reg in inner.split(',').map(str::trim).filter(|r| !r.is_empty()) {
        let size = if reg.starts_with('d') { 8 } else { 4 };
        let count = match reg.split_once('-') {
            Some((a, b)) => {
                let n = |r: &str| r.trim().get(1..).and_then(|d| d.parse::<u64>().ok());
                match (n(a), n(b)) {
                    (Some(a), Some(b)) if b >= a => b - a + 1,
                    _ => bail!("register range {reg:?}"),
                }
            }
            None => 1,
        };
        total += size * count;
    }
    Ok(total)
}

/// True when `jump` (`mov pc, rN`) ends a jump table of its own function (which ends before
/// `end`): among the few instructions before it, the last two that write rN are `adr rN, #t`
/// then `add rN, rN, rM, lsl #2`, and the table `adr` points at starts after the jump, inside
/// the function.
pub(super) fn jump_table_within(insns: &[Insn], jump: &Insn, end: u32) -> bool {
    let Some(reg) = jump
        .operands
        .strip_prefix("pc, ")
        .map(str::trim)
        .filter(|r| !r.is_empty())
    else {
        return false;
    };
    if !is_op(&jump.mnemonic, "mov") {
        return false;
    }
    let Some(k) = insns.iter().position(|i| i.addr == jump.addr) else {
        return false;
    };
    let ops = |i: &Insn| -> Vec<String> {
        i.operands
            .split(',')
            .map(|o| o.trim().to_string())
            .collect()
    };
    // The writes of rN before the jump, nearest first (within 6 instructions).
    let mut writes = insns
        .get(k.saturating_sub(6)..k)
        .unwrap_or(&[])
        .iter()
        .rev()
        .filter(|i| ops(i).first().is_some_and(|d| d == reg));
    let (Some(add), Some(adr)) = (writes.next(), writes.next()) else {
        return false;
    };
    let (add_ops, adr_ops) = (ops(add), ops(adr));
    let is_add = is_op(&add.mnemonic, "add")
        && add_ops.len() == 4
        && add_ops.get(1).is_some_and(|a| a == reg)
        && add_ops.get(3).is_some_and(|s| s == "lsl #2");
    if !(is_add && is_op(&adr.mnemonic, "adr") && adr_ops.len() == 2) {
        return false;
    }
    // Thumb: `adr` is relative to the word-aligned pc (the instruction + 4).
    let table = adr_ops
        .get(1)
        .and_then(|o| imm(o))
        .map(|o| i64::from((adr.addr + 4) & !3) + o);
    table.is_some_and(|t| t > i64::from(jump.addr) && t < i64::from(end))
}

/// `pc` written from anything but the stack (a return pops it): `mov pc, rN`,
/// `ldr pc, [rN]`, `ldm rN, {…, pc}`.
pub(super) fn loads_pc_indirectly(i: &Insn) -> bool {
    let (m, ops) = (i.mnemonic.as_str(), i.operands.as_str());
    if is_op(m, "pop") {
        return false;
    }
    let first = ops.split([',', ' ']).next().unwrap_or("");
    (first == "pc" && !ops.contains("[sp"))
        || (m.starts_with("ldm") && ops.contains("pc}") && !first.starts_with("sp"))
}

/// Bytes the instruction takes off the stack (for functions without an entry); `Err` when
/// the amount is not a constant.
pub(super) fn stack_decrement(i: &Insn) -> Result<u64> {
    let m = base(&i.mnemonic);
    let ops = i.operands.as_str();
    if is_op(m, "push") || is_op(m, "vpush") {
        return reg_list_bytes(ops);
    }
    if (m.starts_with("stmdb") || m.starts_with("vstmdb")) && ops.starts_with("sp!") {
        return reg_list_bytes(ops);
    }
    if m.starts_with("str") || m.starts_with("vstr") {
        // `str r11, [sp, #-4]!`, `strd r4, r5, [sp, #-8]!`
        if let Some((_, addr)) = ops.split_once("[sp, ") {
            if let Some(off) = addr.strip_suffix("]!").and_then(imm) {
                return Ok(u64::try_from(-off).unwrap_or(0));
            }
        }
        return Ok(0);
    }
    if m.starts_with("sub") || m.starts_with("add") {
        let parts: Vec<&str> = ops.split(',').map(str::trim).collect();
        let amount = match parts.as_slice() {
            ["sp", x] | ["sp", "sp", x] => *x,
            _ => return Ok(0), // sp is not the destination, or restored from a frame pointer
        };
        let Some(v) = imm(amount) else {
            bail!("sp adjusted by a register: `{} {}`", i.mnemonic, i.operands);
        };
        let v = if m.starts_with("sub") { v } else { -v };
        return Ok(u64::try_from(v).unwrap_or(0));
    }
    Ok(0)
}
