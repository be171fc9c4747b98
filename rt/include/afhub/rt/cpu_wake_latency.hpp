// Holding the kernel's CPU wake-up latency limit (PM QoS, /dev/cpu_dma_latency), as
// real-time programs such as cyclictest do. At 0 an idle CPU polls instead of
// entering a sleep state: a thread woken on it (by a packet, a futex, a timer) runs
// within microseconds. On a virtual machine, a halted vCPU takes tens of
// microseconds to wake, which otherwise lands on every message that crosses a
// process. The cost: idle cores stay busy (power, or the host's CPU time).
#pragma once

namespace afhub {

constexpr const char* kCpuWakeLatencyDevice = "/dev/cpu_dma_latency";
// The largest limit a program here asks for: beyond 1 ms it changes nothing a
// 1 kHz loop would notice.
constexpr int kMaxCpuWakeLatencyUs = 1000;

// The option's value: afhub::Error unless 0 to kMaxCpuWakeLatencyUs, or -1 (leave the
// CPUs as they are) when not `given` (the option's default: written, it is refused).
void check_cpu_wake_latency_option(int microseconds, bool given = false);

// Asks for wake-ups within `microseconds` until this process exits (the kernel drops
// the request when the file closes, however the process ends). False, said on stderr
// naming `who` and what to do, when refused; the process then runs without it.
// `device` is for tests.
bool hold_cpu_wake_latency(int microseconds, const char* who,
                           const char* device = kCpuWakeLatencyDevice);

}  // namespace afhub
