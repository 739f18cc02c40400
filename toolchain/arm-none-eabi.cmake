# Bare-metal Cortex-M: builds core/ and the MCU example only (GYROCHAR_CORE_ONLY).
# Debian packages: gcc-arm-none-eabi, libstdc++-arm-none-eabi-newlib, libnewlib-arm-none-eabi.
# GYROCHAR_MCU_CPU selects cortex-m4 (FPv4-SP) or cortex-m7 (FPv5-D16).
set(CMAKE_SYSTEM_NAME Generic)
set(CMAKE_SYSTEM_PROCESSOR arm)
set(CMAKE_C_COMPILER arm-none-eabi-gcc)
set(CMAKE_CXX_COMPILER arm-none-eabi-g++)
set(CMAKE_TRY_COMPILE_TARGET_TYPE STATIC_LIBRARY)

set(GYROCHAR_MCU_CPU "cortex-m4" CACHE STRING "cortex-m4 or cortex-m7")
if(GYROCHAR_MCU_CPU STREQUAL "cortex-m7")
  set(fpu "-mfpu=fpv5-d16")
else()
  set(fpu "-mfpu=fpv4-sp-d16")
endif()
set(CMAKE_CXX_FLAGS_INIT "-mcpu=${GYROCHAR_MCU_CPU} -mthumb -mfloat-abi=hard ${fpu} -fno-exceptions -fno-rtti -ffunction-sections -fdata-sections -Wno-psabi")
set(CMAKE_EXE_LINKER_FLAGS_INIT "--specs=nano.specs --specs=nosys.specs -Wl,--gc-sections")
set(GYROCHAR_CORE_ONLY ON CACHE BOOL "" FORCE)
