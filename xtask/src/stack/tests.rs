//! Unit tests of the parser and the walk on hand-written tool output.

use super::parse::*;
use super::*;

/// `main` calls `work` (entry 16) and tail-calls `helper`; `work` calls `__aeabi_dmul`
/// (no entry: push 8 + vpush {d8, d9} 16 + sub 24 = 48); lld padding after `helper`.
const DIS: &str = "
fw:	file format elf32-littlearm

Disassembly of section .text:

00000100 <main>:
     100: b580         	push	{r7, lr}
     102: f000 f805    	bl	0x110 <work>            @ imm = #0xa
     106: 2800         	cmp	r0, #0x0
     108: d0fc         	beq	0x104 <main+0x4>        @ imm = #-0x8
     10a: e8bd 4080    	pop.w	{r7, lr}
     10e: f000 b809    	b.w	0x124 <helper>          @ imm = #0x12

00000110 <work>:
     110: b580         	push	{r7, lr}
     112: f000 f80b    	bl	0x12c <__aeabi_dmul>    @ imm = #0x16
     116: bd80         	pop	{r7, pc}
     118: 18 43 00 20  	.word	0x20004318
     11c: bf00         	nop
     11e: bf00         	nop
     120: bf00         	nop
     122: bf00         	nop

00000124 <helper>:
     124: b082         	sub	sp, #0x8
     126: b002         	add	sp, #0x8
     128: 4770         	bx	lr
     12a: d4d4         	bmi	0xd6 <foo+0x2>          @ imm = #-0x58

0000012c <__aeabi_dmul>:
     12c: b580         	push	{r7, lr}
     12e: ed2d 8b04    	vpush	{d8, d9}
     132: b086         	sub	sp, #0x18
     134: f84d bd04    	str	r11, [sp, #-4]!
     138: b006         	add	sp, #0x18
     13a: bd80         	pop	{r7, pc}
";

/// `helper` is an alias of the entry that also names `other`.
const SYMS: &str = "
SYMBOL TABLE:
00000100 g     F .text	00000010 main
00000111 l     F .text	00000014 _ZN4work17h0123456789abcdefE
00000124 l     F .text	00000008 .hidden helper_alias
0000012c l     F .text	00000010 __aeabi_dmul
00000124 l       .text	00000000 $t
";

const SIZES: &str = "
StackSizes [
  Entry {
    Functions: [main]
    Size: 0x8
  }
  Entry {
    Functions: [_ZN4work17h0123456789abcdefE]
    Size: 0x10
  }
  Entry {
    Functions: [other, helper_alias]
    Size: 0x8
  }
]
";

fn graph(dis: &str) -> Graph {
    let functions = parse_disassembly(dis).unwrap();
    let sizes = parse_stack_sizes(SIZES).unwrap();
    build(&functions, &parse_symbols(SYMS), &sizes)
}

#[test]
fn parses_readobj_and_symbols() {
    let sizes = parse_stack_sizes(SIZES).unwrap();
    assert_eq!(sizes.len(), 3);
    assert_eq!(
        sizes[2],
        (vec!["other".to_string(), "helper_alias".to_string()], 8)
    );
    let syms = parse_symbols(SYMS);
    assert_eq!(syms.get("_ZN4work17h0123456789abcdefE"), Some(&0x110));
    assert_eq!(syms.get("helper_alias"), Some(&0x124));
    assert_eq!(syms.get("$t"), None);
}

#[test]
fn parses_objdump_and_drops_lld_padding() {
    let f = parse_disassembly(DIS).unwrap();
    let names: Vec<&str> = f.iter().map(|f| f.name.as_str()).collect();
    assert_eq!(names, ["main", "work", "helper", "__aeabi_dmul"]);
    assert_eq!(f[0].insns.len(), 6);
    assert_eq!(f[0].insns[1].mnemonic, "bl");
    assert_eq!(f[0].insns[1].bytes, "f000 f805");
    assert!(f[0].insns[1].operands.starts_with("0x110 <work>"));
    assert_eq!(f[2].insns.len(), 3, "the d4d4 padding is not code");
}

#[test]
fn tail_call_and_prologue_frame() {
    let g = graph(DIS);
    let main = g.find("main").unwrap();
    let callees: Vec<(&str, Edge)> = g.nodes[main]
        .callees
        .iter()
        .map(|(c, e)| (g.nodes[*c].name.as_str(), *e))
        .collect();
    assert_eq!(
        callees,
        [("work", Edge::Call), ("helper", Edge::TailCall)],
        "the beq inside main is no edge, the b.w to helper is a tail call"
    );
    let dmul = &g.nodes[g.find("__aeabi_dmul").unwrap()];
    assert_eq!(dmul.source, Source::Prologue);
    assert_eq!(dmul.frame, 8 + 16 + 24 + 4);
    let helper = &g.nodes[g.find("helper").unwrap()];
    assert_eq!((helper.frame, helper.source), (8, Source::StackSizes));
    let p = g.worst(main).unwrap();
    assert_eq!(p.total, 8 + 16 + 52);
    let names: Vec<&str> = p
        .steps
        .iter()
        .map(|s| g.nodes[s.node].name.as_str())
        .collect();
    assert_eq!(names, ["main", "work", "__aeabi_dmul"]);
}

#[test]
fn a_known_indirect_call_is_an_edge_to_its_one_target() {
    let dis = DIS
        .replace(
            "     112: f000 f80b    	bl	0x12c <__aeabi_dmul>    @ imm = #0x16",
            "     112: 4798         	blx	r3",
        )
        .replace(
            "00000110 <work>:",
            "00000110 <<heapless::vec::Vec<F, 48> as pfe_core::output::FeatureSink>::retain>:",
        )
        .replace(
            "0000012c <__aeabi_dmul>:",
            "0000012c <pfe_core::sift::sift::{closure#0}>:",
        );
    let g = graph(&dis);
    let path = g.worst(g.find("main").unwrap()).unwrap();
    let names: Vec<&str> = path
        .steps
        .iter()
        .map(|s| g.nodes[s.node].name.as_str())
        .collect();
    assert_eq!(
        names.last(),
        Some(&"pfe_core::sift::sift::{closure#0}"),
        "{names:?}"
    );
    // The same call anywhere else is still an error.
    let other = dis.replace(
        "pfe_core::output::FeatureSink>::retain",
        "pfe_core::output::FeatureSink>::other",
    );
    let g = graph(&other);
    assert!(g.worst(g.find("main").unwrap()).is_err());
}

#[test]
fn indirect_call_is_an_error_when_reachable() {
    let dis = DIS.replace(
        "     112: f000 f80b    	bl	0x12c <__aeabi_dmul>    @ imm = #0x16",
        "     112: 4798         	blx	r3",
    );
    let g = graph(&dis);
    let err = g.worst(g.find("main").unwrap()).unwrap_err().to_string();
    assert!(
        err.contains("indirect call") && err.contains("blx r3"),
        "{err}"
    );
    assert!(err.contains("main -> work"), "{err}");
    // Not reachable from __aeabi_dmul: fine.
    assert!(g.worst(g.find("__aeabi_dmul").unwrap()).is_ok());
    let bx = DIS.replace(
        "     128: 4770         	bx	lr",
        "     128: 4718         	bx	r3",
    );
    let g = graph(&bx);
    assert!(g.worst(g.find("main").unwrap()).is_err());
}

#[test]
fn recursion_is_an_error() {
    // __aeabi_dmul tail-calls work, which calls __aeabi_dmul.
    let dis = DIS.replace(
        "     13a: bd80         	pop	{r7, pc}",
        "     13a: f7ff bfe9    	b.w	0x110 <work>",
    );
    let g = graph(&dis);
    let err = g.worst(g.find("main").unwrap()).unwrap_err().to_string();
    assert!(err.contains("cycle work -> __aeabi_dmul -> work"), "{err}");
}

#[test]
fn register_sp_adjustment_and_mid_function_branch_are_errors() {
    let dis = DIS.replace(
        "     132: b086         	sub	sp, #0x18",
        "     132: ebad 0d03    	sub.w	sp, sp, r3",
    );
    let g = graph(&dis);
    let err = g.worst(g.find("main").unwrap()).unwrap_err().to_string();
    assert!(err.contains("sp adjusted by a register"), "{err}");
    let dis = DIS.replace("b.w	0x124 <helper>", "b.w	0x126 <helper+0x2>");
    let g = graph(&dis);
    let err = g.worst(g.find("main").unwrap()).unwrap_err().to_string();
    assert!(err.contains("branch into helper at +0x2"), "{err}");
}

#[test]
fn mnemonics() {
    assert!(is_op("bl", "bl") && is_op("blne", "bl"));
    assert!(!is_op("bls", "bl") && is_op("bls", "b"));
    assert!(!is_op("blo", "bl") && is_op("blo", "b") && is_op("blt.w", "b"));
    assert!(!is_op("blx", "bl") && is_op("blx", "blx") && !is_op("bic", "b"));
    assert!(is_op("bxne", "bx") && !is_op("bx", "b"));
    assert_eq!(reg_list_bytes("{r4, r5, r6, r7, lr}").unwrap(), 20);
    assert_eq!(reg_list_bytes("{d8-d11}").unwrap(), 32);
    assert_eq!(reg_list_bytes("{s16, s17}").unwrap(), 8);
    let insn = |m: &str, o: &str| Insn {
        addr: 0,
        bytes: String::new(),
        mnemonic: m.into(),
        operands: o.into(),
    };
    assert!(loads_pc_indirectly(&insn("ldr.w", "pc, [r3, r0, lsl #2]")));
    assert!(loads_pc_indirectly(&insn("mov", "pc, r2")));
    assert!(loads_pc_indirectly(&insn("ldm.w", "r3, {r4, pc}")));
    assert!(!loads_pc_indirectly(&insn("ldr", "pc, [sp], #4")));
    assert!(!loads_pc_indirectly(&insn("ldm.w", "sp!, {r4, pc}")));
    assert!(!loads_pc_indirectly(&insn("pop.w", "{r4, r5, pc}")));
    assert!(!loads_pc_indirectly(&insn("ldr", "r0, [pc, #0x48]")));
    assert_eq!(imm("#0xf38"), Some(0xf38));
    assert_eq!(imm("#-4"), Some(-4));
}

#[test]
fn short_names() {
    assert_eq!(
        short("<lms2xx::driver::Driver<firmware_qemu::scanner_uart::ScannerUart, firmware_qemu::time::Delay>>::init"),
        "Driver::init"
    );
    assert_eq!(
        short("pfe_qemu::fw::__cortex_m_rt_main"),
        "fw::__cortex_m_rt_main"
    );
    assert_eq!(
        short("<semihosting::io::stdio::Stdout as semihosting::io::Write>::write_all"),
        "Stdout::write_all"
    );
    assert_eq!(short("defmt::export::fmt::<u32>"), "export::fmt");
    assert_eq!(short("__aeabi_dmul"), "__aeabi_dmul");
}

#[test]
fn bound_adds_the_exception_frames() {
    let g = graph(DIS);
    let main = g.worst(g.find("main").unwrap()).unwrap();
    let helper = g.worst(g.find("helper").unwrap()).unwrap();
    let b = Bound {
        graph: g.clone(),
        main: main.clone(),
        handler: helper.clone(),
        handlers: vec![("helper".into(), 8)],
        hard_fault: helper,
    };
    assert_eq!(b.with_interrupt(), 76 + 8 + 108);
    assert_eq!(b.total(), 76 + 8 + 108 + 8 + 108);
    assert!(b.text().contains("static worst-case stack bound"));
    assert!(b.markdown("test").contains("| **76** |"));
}

#[test]
fn a_jump_table_in_its_own_function_is_no_indirect_jump() {
    use super::parse::{jump_table_within, Insn};
    let insn = |addr: u32, mnemonic: &str, operands: &str| Insn {
        addr,
        bytes: String::new(),
        mnemonic: mnemonic.into(),
        operands: operands.into(),
    };
    // As rustc laid out a `match` in pfe-qemu's main: the table of branches right after it.
    let code = [
        insn(0x20e6, "adr.w", "r6, #12"),
        insn(0x20ea, "adds", "r0, r3, #0x5"),
        insn(0x20ec, "add.w", "r6, r6, r1, lsl #2"),
        insn(0x20f0, "mov", "pc, r6"),
    ];
    assert!(jump_table_within(&code, &code[3], 0x3000));
    let code = [
        insn(0x20e8, "adr.w", "r6, #8"),
        insn(0x20ec, "add.w", "r6, r6, r1, lsl #2"),
        insn(0x20f0, "mov", "pc, r6"),
    ];
    let jump = &code[2];
    assert!(jump_table_within(&code, jump, 0x3000));
    // The table past the function's end, or another register: still an indirect jump.
    assert!(!jump_table_within(&code, jump, 0x20f2));
    let other = [
        insn(0x20e8, "adr.w", "r5, #8"),
        insn(0x20ec, "add.w", "r6, r6, r1, lsl #2"),
        insn(0x20f0, "mov", "pc, r6"),
    ];
    assert!(!jump_table_within(&other, &other[2], 0x3000));
}
