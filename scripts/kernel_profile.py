#!/usr/bin/env python3
"""Where a render's time goes inside lavapipe's JIT-compiled kernel, from the machine code.

    python3 scripts/kernel_profile.py [SCENE] [--width W] [--height H] [--seconds S]
        [--warm-up S] [--caustica BIN] [--top N] [--keep FOLDER]

Starts `caustica render SCENE` for long enough, samples it with `perf record` (with the top of
each sample's stack), copies the JIT's executable memory out of the running process with gdb
(`dump binary memory`), and prints:

- how the samples split between the kernel's own code, the small functions it calls, and the rest
  of the process;
- the samples inside the small functions charged to their call sites in the kernel (the first word
  of the sampled stack is the return address: the functions make no frame), and summed by the
  texel buffer each call site fetches from;
- the kernel's own samples by instruction class (each sample charged to the instruction before
  it, for the sampling skid).

Needs `perf`, `gdb` and `objdump` (binutils), and permission to attach to the process (root, or
`kernel.yama.ptrace_scope` 0 and `kernel.perf_event_paranoid` at most 2). lavapipe only: on a GPU
the kernel does not run in the process. The driver is the one the environment selects
(VK_DRIVER_FILES; source `.lavapipe/env` for Mesa 25); the meshes' scenes need $CAUSTICA_DATA
(default ../shared/data).

Why it is built this way, and what Mesa 25.0.7 showed (docs/benchmarks/history.md, 2026-12-06, `273e196`): gallivm
compiles each `texelFetch` as an indirect call through the descriptor into a small function, so
`perf report` can only say that a fifth to a third of the time is in anonymous 4 KiB pages; the
call sites say which buffer's fetches those are. A call site's buffer is read from the code before
the call, which loads the fetch function's address from lavapipe's descriptor of that binding:
`mov 0x<offset>(%rsi),%rax` with offset = 0xf8 + 0x100 x binding in Mesa 25.0.7 (read from its
machine code, not from a documented interface: another Mesa version may lay descriptors out
otherwise, and the script then prints the raw offsets).
"""

import argparse
import collections
import contextlib
import os
import re
import signal
import subprocess
import sys
import tempfile
import time
from pathlib import Path

REPO = Path(__file__).resolve().parent.parent
# Mesa 25.0.7's lavapipe descriptor of binding b sits at 0x100 x b; the fetch function's pointer
# is 0xf8 into it (see the docstring).
DESCRIPTOR_STRIDE, FETCH_FUNCTION_AT = 0x100, 0xF8
# A perf sample of this script's `perf record` (sample type IP | TID | TIME | ADDR | PERIOD |
# CALLCHAIN | REGS_USER | STACK_USER | DATA_SRC, as --call-graph dwarf sets it): the stack's first
# bytes follow the registers. Parsed from `perf report -D`'s raw dump, checked against the IP.
INSTRUCTION = re.compile(r"^\s*([0-9a-f]+):\t(?:[0-9a-f]{2} )+\s*\t(.*)$")


def binding_names():
    """Binding number -> buffer name, from src/render/bindings.rs's table."""
    text = (REPO / "src/render/bindings.rs").read_text()
    return {int(b): name for b, name in re.findall(r'binding: (\d+), name: "(\w+)"', text)}


def executable_mappings(pid):
    """The process's anonymous executable mappings (the JIT's code): [(start, end)]."""
    maps = []
    for line in Path(f"/proc/{pid}/maps").read_text().splitlines():
        fields = line.split()
        if fields[1] == "r-xp" and len(fields) == 5:
            start, end = (int(x, 16) for x in fields[0].split("-"))
            maps.append((start, end))
    return maps


def dump_code(pid, maps, folder):
    """Copies each mapping out of the process with gdb; returns {start: file}."""
    files = {start: folder / f"code_{start:x}.bin" for start, _ in maps}
    script = folder / "dump.gdb"
    script.write_text("".join(f"dump binary memory {files[s]} {s:#x} {e:#x}\n" for s, e in maps))
    subprocess.run(["gdb", "-p", str(pid), "-batch", "-x", str(script)], stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, check=False)
    missing = [f for f in files.values() if not f.exists()]
    if missing:
        sys.exit(f"kernel_profile.py: gdb could not read the JIT's code from process {pid} (attach permission?)")
    return files


def disassemble(start, path):
    """[(address, instruction text)] of a dumped mapping."""
    out = subprocess.run(["objdump", "-D", "-b", "binary", "-m", "i386:x86-64", f"--adjust-vma={start:#x}", str(path)],
                         capture_output=True, text=True, check=True).stdout
    return [(int(m.group(1), 16), m.group(2).strip()) for m in map(INSTRUCTION.match, out.splitlines()) if m]


def samples(perf_data):
    """(ip, first stack word) of each sample, from perf's raw dump."""
    dump = subprocess.run(["perf", "report", "-D", "-i", str(perf_data)], capture_output=True, text=True, check=False).stdout
    records, record = [], None
    for line in dump.splitlines():
        if "raw event: size" in line:
            record = bytearray()
            records.append(record)
        elif record is not None:
            m = re.match(r"\.\s+[0-9a-f]{4}:\s+((?:[0-9a-f]{2} ){1,16})", line)
            if m:
                record += bytes.fromhex(m.group(1).replace(" ", ""))
    # PERF_RECORD_SAMPLE is type 9; its IP follows the 8-byte header. The stack's bytes come after
    # a size word that follows 20 user registers (--user-regs default on x86-64: mask 0xff0fff).
    stack_at = 8 + 8 + 8 + 8 + 8 + 8 + 8 + 8 + 20 * 8 + 8
    out = []
    for r in records:
        if len(r) >= stack_at + 8 and int.from_bytes(r[0:4], "little") == 9:
            out.append((int.from_bytes(r[8:16], "little"), int.from_bytes(r[stack_at:stack_at + 8], "little")))
    return out


def instruction_class(text):
    op = text.split()[0] if text else ""
    stack = "rsp" in text
    if stack and op.startswith(("vmov", "mov", "vpblendm", "vpinsr", "vpextr", "vbroadcast")):
        return "stack loads and stores (spills, private arrays)"
    if stack:
        return "other instructions with a stack operand"
    if op.startswith("call"):
        return "calls"
    if op.startswith("j"):
        return "branches"
    if op.startswith("k"):
        return "mask-register operations"
    if "(" in text:
        return "other memory accesses"
    if op.startswith(("vblend", "vpblend", "vmovdqa", "vmovdqu", "vmovaps", "vmovups")):
        return "register moves and blends"
    if op.startswith(("vcmp", "vpcmp")):
        return "compares"
    if op.startswith(("vmul", "vadd", "vsub", "vfmadd", "vfmsub", "vfnm", "vdiv", "vmin", "vmax", "vrcp", "vsqrt")):
        return "float arithmetic"
    if op.startswith(("vpextr", "vpinsr", "vextract", "vinsert", "vpbroadcast", "vbroadcast", "vperm", "vpshuf", "vshuf", "vpunpck", "vunpck")):
        return "lane inserts, extracts and shuffles"
    return "integer and other"


def call_site_buffer(code, index):
    """The descriptor offset the call at code[index] takes its function from, or None."""
    for _, text in reversed(code[max(index - 40, 0):index]):
        m = re.search(r"mov\s+0x([0-9a-f]+)\(%rsi\),%rax", text)
        if m:
            return int(m.group(1), 16)
    return None


def report(hits, maps, code_files, names, top):
    total = len(hits)
    kernel_start, kernel_end = max(maps, key=lambda m: m[1] - m[0])
    small = [(s, e) for s, e in maps if (s, e) != (kernel_start, kernel_end)]
    in_kernel = [h for h in hits if kernel_start <= h[0] < kernel_end]
    in_small = [h for h in hits if any(s <= h[0] < e for s, e in small)]
    pct = lambda n: f"{100 * n / total:5.1f} %"
    print(f"{total} samples")
    print(f"  the kernel's own code ({(kernel_end - kernel_start) // 1024} KiB): {pct(len(in_kernel))}")
    print(f"  the small functions it calls ({len(small)} mappings): {pct(len(in_small))}")
    print(f"  elsewhere (driver, caustica, kernel): {pct(total - len(in_kernel) - len(in_small))}")

    code = disassemble(kernel_start, code_files[kernel_start])
    at = {address: i for i, (address, _) in enumerate(code)}
    by_buffer, by_site = collections.Counter(), collections.Counter()
    for _, returns_to in in_small:
        call = next((at[returns_to - n] for n in range(2, 8) if returns_to - n in at and code[at[returns_to - n]][1].startswith("call")), None)
        offset = call_site_buffer(code, call) if call is not None else None
        if offset is None:
            buffer = "call site not found"
        elif (offset - FETCH_FUNCTION_AT) % DESCRIPTOR_STRIDE == 0 and (offset - FETCH_FUNCTION_AT) // DESCRIPTOR_STRIDE in names:
            binding = (offset - FETCH_FUNCTION_AT) // DESCRIPTOR_STRIDE
            buffer = f"{names[binding]} (binding {binding})"
        else:
            buffer = f"descriptor offset {offset:#x}"
        by_buffer[buffer] += 1
        by_site[(buffer, returns_to)] += 1
    print("\nthe small functions' samples by the buffer their call site fetches from:")
    for buffer, n in by_buffer.most_common():
        sites = sorted((v for (b, _), v in by_site.items() if b == buffer), reverse=True)
        print(f"  {pct(n)}  {buffer}: {len(sites)} call sites, the busiest " + ", ".join(pct(v).strip() for v in sites[:4]))

    classes = collections.Counter()
    counts = collections.Counter(ip for ip, _ in in_kernel)
    for i, (address, _) in enumerate(code):
        if counts[address]:
            classes[instruction_class(code[max(i - 1, 0)][1])] += counts[address]
    placed = sum(classes.values())
    print(f"\nthe kernel's own samples by instruction class ({pct(placed).strip()} of all samples fall on an instruction of the dump):")
    for cls, n in classes.most_common():
        print(f"  {pct(n)}  {cls}")
    if top:
        # Each sample charged to the instruction before it, as the classes are, with the address's
        # offset into the kernel: enough to tell a spill (a fixed offset from %rsp) from a private
        # array's lane-by-lane access (an address computed in a register).
        charged = collections.Counter()
        for i, (address, _) in enumerate(code):
            if counts[address]:
                charged[max(i - 1, 0)] += counts[address]
        print(f"\nthe {top} hottest instructions of the kernel:")
        for i, n in charged.most_common(top):
            print(f"  {pct(n)}  +{code[i][0] - kernel_start:#07x}  {code[i][1]}")


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("scene", nargs="?", default="scenes/bunny_cornell.toml")
    parser.add_argument("--width", type=int, default=256)
    parser.add_argument("--height", type=int, default=256)
    parser.add_argument("--seconds", type=float, default=10.0, help="how long to sample (default 10)")
    parser.add_argument("--warm-up", type=float, default=8.0, help="seconds before sampling starts: the kernel's compile and first dispatch (default 8)")
    parser.add_argument("--caustica", default=str(REPO / "target/release/caustica"))
    parser.add_argument("--top", type=int, default=0, help="also list the N hottest instructions of the kernel")
    parser.add_argument("--keep", metavar="FOLDER", help="keep the machine code, perf's samples and the render in FOLDER "
                        "(objdump -D -b binary -m i386:x86-64 FILE reads a mapping; its start address is in its name)")
    args = parser.parse_args()
    env = dict(os.environ)
    env.setdefault("CAUSTICA_DATA", str(REPO.parent / "shared" / "data"))
    if args.keep:
        Path(args.keep).mkdir(parents=True, exist_ok=True)
    with (contextlib.nullcontext(str(Path(args.keep).resolve())) if args.keep else tempfile.TemporaryDirectory()) as tmp:
        folder = Path(tmp)
        seconds = args.warm_up + args.seconds + 30
        render = subprocess.Popen([args.caustica, "render", args.scene, "--width", str(args.width), "--height", str(args.height),
                                   "--spp", "1000000", "--time", f"{seconds}s", "--output", str(folder / "render.pfm")],
                                  cwd=REPO, env=env, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
        try:
            time.sleep(args.warm_up)
            if render.poll() is not None:
                sys.exit(f"kernel_profile.py: the render ended early:\n{render.stderr.read()}")
            perf_data = folder / "perf.data"
            subprocess.run(["perf", "record", "-F", "4000", "--call-graph", "dwarf,64", "-p", str(render.pid), "-o", str(perf_data),
                            "--", "sleep", str(args.seconds)], stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, check=True)
            maps = executable_mappings(render.pid)
            if not maps:
                sys.exit("kernel_profile.py: no JIT code in the process (is the device lavapipe?)")
            code_files = dump_code(render.pid, maps, folder)
        finally:
            render.send_signal(signal.SIGKILL)
            render.wait()
        report(samples(perf_data), maps, code_files, binding_names(), args.top)


if __name__ == "__main__":
    main()
