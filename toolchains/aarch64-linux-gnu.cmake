# Cross-compile for ARM64 Linux (Jetson / Raspberry Pi class Cortex-A). Tests run under qemu-user
# through CMAKE_CROSSCOMPILING_EMULATOR, so `ctest --preset aarch64` exercises the ARM64 ISA.
set(CMAKE_SYSTEM_NAME Linux)
set(CMAKE_SYSTEM_PROCESSOR aarch64)
set(CMAKE_C_COMPILER aarch64-linux-gnu-gcc)
set(CMAKE_CXX_COMPILER aarch64-linux-gnu-g++)
set(CMAKE_CROSSCOMPILING_EMULATOR qemu-aarch64;-L;/usr/aarch64-linux-gnu)
set(CMAKE_FIND_ROOT_PATH /usr/aarch64-linux-gnu)
set(CMAKE_FIND_ROOT_PATH_MODE_PROGRAM NEVER)
set(CMAKE_FIND_ROOT_PATH_MODE_LIBRARY ONLY)
set(CMAKE_FIND_ROOT_PATH_MODE_INCLUDE BOTH)  # header-only Eigen / Catch2 from /usr/include
set(CMAKE_FIND_ROOT_PATH_MODE_PACKAGE BOTH)
# CPU tuning for everything the build compiles (library, tools, tests): the baseline ISA by default;
# pass e.g. -DGSF_CPU_TUNING=-mcpu=cortex-a72 (Raspberry Pi 4 class) or -mcpu=cortex-a78ae (automotive
# Orin class) to tune for a core. The root CMakeLists.txt adds it with add_compile_options, so changing
# it in an existing build tree takes effect on the next build.
set(GSF_CPU_TUNING "-march=armv8-a" CACHE STRING "CPU flags for the aarch64 build, e.g. -mcpu=cortex-a72")
