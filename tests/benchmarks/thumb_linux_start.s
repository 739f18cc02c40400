@ Entry point for running Cortex-M code (Thumb-2, the MCU preset's instruction set) as a Linux
@ process under qemu-arm user mode, so that its instructions can be counted (toolchain/benchmarks.sh):
@ main(argc, argv) from the process stack, then the exit system call with main's result.
.syntax unified
.thumb
.global _start
.type _start, %function
_start:
  ldr r0, [sp]
  add r1, sp, #4
  bl main
  movs r7, #1
  svc 0
