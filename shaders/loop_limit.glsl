// Loops on devices that end them early. llvmpipe (lavapipe) before Mesa 24 stops every loop of an
// invocation once 65,535 loop iterations have run in total (gallivm's LP_MAX_TGSI_LOOP_ITERATIONS:
// one counter per SIMD batch of invocations, shared by all its loops), silently: samples would be
// lost or cut short without an error. The host probes each device for such a limit
// (src/gpu/loop_limit.rs) and, where there is one, plans dispatches from the iterations counted
// here; on every device, loop_limit_intact() tells an invocation whether it was cut short.

// COUNT_LOOP_ITERATIONS (injected by the host: 1 on devices with a limit) counts what the limit
// counts: one iteration per pass of the whole subgroup through a loop body, so the first active
// invocation counts it, and report_loop_iterations() sums them over the subgroup and keeps the
// most in stats.max_loop_iterations. Every invocation of the subgroup must call it (in or out of
// the image). (pathtrace.comp enables the subgroup extensions; unused, they cost nothing.)
#if COUNT_LOOP_ITERATIONS
uint loop_iterations = 0u;
#define LOOP_ITERATION() if (subgroupElect()) loop_iterations += 1u
void report_loop_iterations() {
    uint subgroup_iterations = subgroupAdd(loop_iterations);
    if (subgroupElect()) atomicMax(stats.max_loop_iterations, subgroup_iterations);
}
#else
#define LOOP_ITERATION()
void report_loop_iterations() {}
#endif

// Whether every loop of this invocation ran to its end. The limit's counter only falls, so once it
// has run out every later loop stops after one iteration: a loop that must run
// pass.loop_check_iterations (2) times and runs fewer shows that some loop may have been cut. The
// count comes from the host so that no compiler can fold the loop away.
bool loop_limit_intact() {
    uint iterations = 0u;
    for (uint i = 0u; i < pass.loop_check_iterations; ++i) iterations += 1u;
    return iterations == pass.loop_check_iterations;
}
