# Bounds on the Cortex-M4F cycles of traced calls, from their executed instructions and the per-instruction cycle
# counts of ARM's Cortex-M4 Technical Reference Manual (r0p1, DDI 0439: "Processor instructions" and "FPU
# instruction set" tables; zero wait states). Each instruction gets its best and worst case there: a load or store
# 1-2 (2, or 1 when pipelined behind another), a branch 1 (not taken) to 1 + P (P, the pipeline refill, 1-3), IT
# 0-1 (folded or not), SDIV/UDIV 2-12, LDM/STM/PUSH/POP 1 + N (+ P when they load pc), VLDR/VSTR 1-2 (2, or 1
# pipelined as a load or store), VLDM/VSTM/VPUSH/VPOP 1 + N (N singles; a double is 2), VMOV between core and FPU
# registers 1-2, VMLA/VMLS/VFMA/VFMS and their negations 3, VDIV/VSQRT 14, every other data-processing or FPU
# instruction 1. Not modelled: flash wait states (a zero-wait-state memory is assumed), interrupts, stalls on an FPU
# result, and the overlap of VDIV/VSQRT with the integer instructions after them (up to 13 cycles each: the count
# of divisions and square roots is printed).
# Input: the image's `objdump -d`, then lines "call pc count" (pc in hex). Output: per call, the low and high bound.
function hex(s,    i, n) {
    n = 0
    s = tolower(s)
    for (i = 1; i <= length(s); i++) n = n * 16 + index("0123456789abcdef", substr(s, i, 1)) - 1
    return n
}
function regs(list,    items, i, n, a, b, k, lo, hi) {  # registers in "{r4, r5, lr}" or "{s16-s23}", doubles twice
    gsub(/[{}]/, "", list)
    k = split(list, items, ",")
    n = 0
    for (i = 1; i <= k; i++) {
        gsub(/ /, "", items[i])
        if (split(items[i], a, "-") == 2) {
            lo = substr(a[1], 2) + 0; hi = substr(a[2], 2) + 0
            n += (hi - lo + 1) * (substr(a[1], 1, 1) == "d" ? 2 : 1)
        } else n += substr(items[i], 1, 1) == "d" ? 2 : 1
    }
    return n
}
FNR == NR {
    if ($0 !~ /^ +[0-9a-f]+:\t/) next
    split($0, f, "\t")
    gsub(/[ :]/, "", f[1])
    addr = hex(f[1])
    op = f[3]; sub(/\..*/, "", op); args = f[4]
    cond = "(eq|ne|cs|cc|hs|lo|mi|pl|vs|vc|hi|ls|ge|lt|gt|le)"
    lo = 1; hi = 1
    if (op ~ "^(vdiv|vsqrt)") { lo = 14; hi = 14; div[addr] = 1 }
    else if (op ~ "^(vmla|vmls|vfma|vfms|vfnma|vfnms|vnmla|vnmls)") { lo = 3; hi = 3 }
    else if (op ~ "^(vldm|vstm|vpush|vpop)") { lo = hi = 1 + regs(args) }
    else if (op ~ "^(vldr|vstr)") { lo = 1; hi = 2 }
    else if (op ~ "^vmov" && args ~ /r[0-9]|lr|ip/) { lo = 1; hi = 2 }
    else if (op ~ "^(ldrd|strd)") { lo = 3; hi = 3 }
    else if (op ~ "^(ldm|stm|push|pop)") { lo = hi = 1 + regs(args); if (args ~ /pc/) { lo += 1; hi += 3 } }
    else if (op ~ "^(ldr|str)") { lo = 1; hi = 2; if (args ~ /^pc,/) { lo += 1; hi += 3 } }
    else if (op ~ "^b" cond "$" || op ~ /^cbn?z$/) { lo = 1; hi = 4 }
    else if (op ~ /^(b|bl|blx|bx)$/) { lo = 2; hi = 4 }
    else if (op ~ "^(sdiv|udiv)") { lo = 2; hi = 12 }
    else if (op ~ "^it" || op == "nop") { lo = 0; hi = 1 }
    low[addr] = lo; high[addr] = hi
    next
}
{
    a = hex($2)
    if (!(a in low)) { unknown[$1] += $3; next }
    l[$1] += $3 * low[a]; h[$1] += $3 * high[a]; n[$1] += $3; d[$1] += $3 * div[a]
    if ($1 + 0 > calls) calls = $1 + 0
}
END {
    for (c = 1; c <= calls; c++)
        printf "   call %d: %d instructions, %d to %d cycles (%.2f to %.2f a instruction; %d divisions and square " \
               "roots)%s\n", c, n[c], l[c], h[c], l[c] / n[c], h[c] / n[c], d[c] + 0,
               unknown[c] ? sprintf(", %d not in the image", unknown[c]) : ""
}
