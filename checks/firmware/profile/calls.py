"""The memory helpers' calls in a firmware's disassembly, with how often each ran and
the size its immediate gives: shared by `aggregate.py` (by caller) and `lines.py` (by
source line)."""
import collections
import re

HELPERS = ("__aeabi_memcpy", "__aeabi_memclr", "__aeabi_memset", "__aeabi_memmove",
           "memcpy", "memset", "memmove")
CALL = re.compile(r"^\s*([0-9a-f]+):.*\bbl\s+0x[0-9a-f]+ <([^>]+)>")
# The size's register: r2 for the copies (dest, src, n), r1 for the AEABI clears and
# sets (dest, n[, c]).
SIZE = {r: re.compile(rf"\b(?:movs?|mov\.w|movw)\s+{r}, #(\d+)") for r in ("r1", "r2")}


def helper_calls(disassembly, runs_to):
    """Yields `(address, helper, executions, bytes)` for each call of a memory helper
    that ran: a call ends its block, so the executions of the blocks whose last
    instruction it is (`runs_to`, by address) are the call's; the bytes are the
    immediate last moved into the size's register (0 if none)."""
    recent = collections.deque(maxlen=6)
    for line in open(disassembly):
        m = CALL.match(line)
        if m and m.group(2).startswith(HELPERS):
            addr, helper = int(m.group(1), 16), m.group(2)
            n = runs_to.get(addr, 0)
            if n:
                reg = "r1" if helper.startswith(("__aeabi_memclr", "__aeabi_memset")) else "r2"
                sized = [int(x) for x in SIZE[reg].findall(" ".join(recent))]
                yield addr, helper, n, sized[-1] if sized else 0
        recent.append(line)
