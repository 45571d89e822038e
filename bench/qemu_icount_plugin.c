/* A qemu-user TCG plugin that turns bench_stages' stage clock into an instruction counter, for
 * instruction counts per stage of the ARM64 build under qemu-aarch64 (Debian's qemu-user supports
 * -plugin but ships no plugin). Counts guest instructions per executed translation block; when the
 * guest calls pread64(fd, buf, 8, GSF_ICOUNT_MAGIC) (bench_stages --icount-file), the count so far is
 * written into the file at that offset first, so the read returns it. Built for the host by
 * bench/stages.sh --arm64-counts:
 *   cc -shared -fPIC -O2 -o qemu_icount_plugin.so bench/qemu_icount_plugin.c
 *   qemu-aarch64 -plugin ./qemu_icount_plugin.so,out=/dev/shm/gsf_icount ... bench_stages --icount-file
 * /dev/shm/gsf_icount The declarations below are the qemu plugin API (version 1, QEMU 7.2) this file uses. */
#include <fcntl.h>
#include <stdint.h>
#include <stdio.h>
#include <string.h>
#include <unistd.h>

#define QEMU_PLUGIN_EXPORT __attribute__((visibility("default")))
typedef uint64_t qemu_plugin_id_t;
typedef struct qemu_info_t qemu_info_t;
struct qemu_plugin_tb;
enum qemu_plugin_op { QEMU_PLUGIN_INLINE_ADD_U64 };
typedef void (*qemu_plugin_vcpu_tb_trans_cb_t)(qemu_plugin_id_t id, struct qemu_plugin_tb* tb);
typedef void (*qemu_plugin_vcpu_syscall_cb_t)(qemu_plugin_id_t id, unsigned int vcpu_index, int64_t num, uint64_t a1,
                                              uint64_t a2, uint64_t a3, uint64_t a4, uint64_t a5, uint64_t a6,
                                              uint64_t a7, uint64_t a8);
void qemu_plugin_register_vcpu_tb_trans_cb(qemu_plugin_id_t id, qemu_plugin_vcpu_tb_trans_cb_t cb);
void qemu_plugin_register_vcpu_tb_exec_inline(struct qemu_plugin_tb* tb, enum qemu_plugin_op op, void* ptr,
                                              uint64_t imm);
size_t qemu_plugin_tb_n_insns(const struct qemu_plugin_tb* tb);
void qemu_plugin_register_vcpu_syscall_cb(qemu_plugin_id_t id, qemu_plugin_vcpu_syscall_cb_t cb);

QEMU_PLUGIN_EXPORT int qemu_plugin_version = 1;

#define GSF_ICOUNT_MAGIC 0x47534600ULL /* must match bench_stages.cpp */
#define AARCH64_NR_PREAD64 67

static uint64_t insns;
static int out_fd = -1;

static void on_tb(qemu_plugin_id_t id, struct qemu_plugin_tb* tb) {
  (void)id;
  qemu_plugin_register_vcpu_tb_exec_inline(tb, QEMU_PLUGIN_INLINE_ADD_U64, &insns, qemu_plugin_tb_n_insns(tb));
}

static void on_syscall(qemu_plugin_id_t id, unsigned int vcpu, int64_t num, uint64_t a1, uint64_t a2, uint64_t a3,
                       uint64_t a4, uint64_t a5, uint64_t a6, uint64_t a7, uint64_t a8) {
  (void)id;
  (void)vcpu;
  (void)a1;
  (void)a2;
  (void)a5;
  (void)a6;
  (void)a7;
  (void)a8;
  if (num == AARCH64_NR_PREAD64 && a3 == 8 && a4 == GSF_ICOUNT_MAGIC && out_fd >= 0) {
    const uint64_t v = insns;
    if (pwrite(out_fd, &v, sizeof v, (off_t)GSF_ICOUNT_MAGIC) != (ssize_t)sizeof v) perror("qemu_icount_plugin");
  }
}

QEMU_PLUGIN_EXPORT int qemu_plugin_install(qemu_plugin_id_t id, const qemu_info_t* info, int argc, char** argv) {
  (void)info;
  for (int i = 0; i < argc; ++i)
    if (strncmp(argv[i], "out=", 4) == 0) out_fd = open(argv[i] + 4, O_RDWR | O_CREAT, 0644);
  if (out_fd < 0) {
    fprintf(stderr, "qemu_icount_plugin: needs out=PATH (qemu reserves file=)\n");
    return 1;
  }
  qemu_plugin_register_vcpu_tb_trans_cb(id, on_tb);
  qemu_plugin_register_vcpu_syscall_cb(id, on_syscall);
  return 0;
}
