# Warnings and sanitizers for the project's own targets (not for third-party headers).
add_library(fibre_warnings INTERFACE)
target_compile_options(fibre_warnings INTERFACE -Wall -Wextra)

if(FIBRE_SANITIZE)
  add_compile_options(-fsanitize=address,undefined -fno-omit-frame-pointer
                      -fno-sanitize-recover=undefined)
  add_link_options(-fsanitize=address,undefined)
endif()
