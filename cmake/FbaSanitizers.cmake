# FBA_SANITIZE=address,undefined or thread: applied to everything this project builds.
if(FBA_SANITIZE)
  set(_fba_san_flags -fsanitize=${FBA_SANITIZE} -fno-omit-frame-pointer -fno-sanitize-recover=all)
  add_compile_options(${_fba_san_flags})
  add_link_options(${_fba_san_flags})
endif()
