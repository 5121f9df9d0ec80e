# Cross-compiling for Cortex-M with Debian's gcc-arm-none-eabi + libnewlib-arm-none-eabi.
#   cmake -S . -B build-m4 -DCMAKE_TOOLCHAIN_FILE=cmake/arm-none-eabi.cmake -DMVT_MCU_CPU=cortex-m4
# MVT_MCU_CPU: cortex-m4 (FPv4 single-precision FPU) or cortex-m7 (FPv5 FPU), hard-float ABI.
set(CMAKE_SYSTEM_NAME Generic)
set(CMAKE_SYSTEM_PROCESSOR arm)
set(CMAKE_C_COMPILER arm-none-eabi-gcc)
set(CMAKE_CXX_COMPILER arm-none-eabi-g++)
set(CMAKE_ASM_COMPILER arm-none-eabi-gcc)
set(CMAKE_TRY_COMPILE_TARGET_TYPE STATIC_LIBRARY)

set(MVT_MCU_CPU "cortex-m4" CACHE STRING "cortex-m4 or cortex-m7")
if(MVT_MCU_CPU STREQUAL "cortex-m4")
  set(_mvt_cpu_flags "-mcpu=cortex-m4 -mthumb -mfloat-abi=hard -mfpu=fpv4-sp-d16")
elseif(MVT_MCU_CPU STREQUAL "cortex-m7")
  set(_mvt_cpu_flags "-mcpu=cortex-m7 -mthumb -mfloat-abi=hard -mfpu=fpv5-d16")
else()
  message(FATAL_ERROR "MVT_MCU_CPU must be cortex-m4 or cortex-m7, not '${MVT_MCU_CPU}'")
endif()
set(CMAKE_C_FLAGS_INIT "${_mvt_cpu_flags} -ffunction-sections -fdata-sections -fcallgraph-info=su")
set(CMAKE_EXE_LINKER_FLAGS_INIT "${_mvt_cpu_flags} -Wl,--gc-sections")

set(CMAKE_FIND_ROOT_PATH_MODE_PROGRAM NEVER)
set(CMAKE_FIND_ROOT_PATH_MODE_LIBRARY ONLY)
set(CMAKE_FIND_ROOT_PATH_MODE_INCLUDE ONLY)
