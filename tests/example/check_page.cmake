# Fails unless PAGE (the guide's page on the C library) contains
# example.c verbatim.
file(READ ${PAGE} page)
file(READ ${EXAMPLE} example)
string(FIND "${page}" "${example}" pos)
if(pos EQUAL -1)
  message(FATAL_ERROR "${PAGE} does not contain tests/example/example.c verbatim")
endif()
