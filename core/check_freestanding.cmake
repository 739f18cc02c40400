# Fails when a file under core/ uses the heap, exceptions, RTTI, iostreams or an OS header.
# Usage: cmake -DCORE_DIR=<core folder> -P check_freestanding.cmake
file(GLOB_RECURSE FILES ${CORE_DIR}/*.hpp ${CORE_DIR}/*.cpp ${CORE_DIR}/*.h ${CORE_DIR}/*.c)
set(forbidden
  "#include[ \t]*<(unistd|pthread|fcntl|iostream|fstream|sstream|thread|mutex|memory|vector|string|map|functional|stdexcept|typeinfo|cstdio|stdio\\.h)>"
  "#include[ \t]*<(sys|linux|asm|net)/"
  "[^a-zA-Z_](malloc|calloc|realloc|free)[ \t]*\\("
  "[^a-zA-Z_]new[ \t]+[A-Za-z_:]"
  "[^a-zA-Z_]delete[ \t]*(\\[\\])?[ \t]*[A-Za-z_]"
  "[^a-zA-Z_](throw|try|catch)[^a-zA-Z_]"
  "(dynamic_cast|typeid)[ \t]*[<(]")
set(failed FALSE)
foreach(file IN LISTS FILES)
  file(STRINGS "${file}" lines)
  set(lineno 0)
  foreach(line IN LISTS lines)
    math(EXPR lineno "${lineno} + 1")
    string(REGEX REPLACE "//.*$" "" code "${line}")
    foreach(pattern IN LISTS forbidden)
      if(code MATCHES "${pattern}")
        message(SEND_ERROR "${file}:${lineno}: not allowed in core/ (${CMAKE_MATCH_0}): ${line}")
        set(failed TRUE)
      endif()
    endforeach()
  endforeach()
endforeach()
if(failed)
  message(FATAL_ERROR "core/ must stay freestanding: standard headers only, no heap, exceptions, RTTI or OS headers")
endif()
