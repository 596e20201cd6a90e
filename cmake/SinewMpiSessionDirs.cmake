# sinew_private_mpi_session_dirs(): gives every test of the calling folder its own Open MPI session
# directory. Open MPI 4.1 creates and removes one shared /tmp/ompi.<host>.<uid> per job, and two jobs
# that start at once under `ctest -j` race on it ("A call to mkdir was unable to create the desired
# directory ... File exists", open-mpi/ompi#8510): CI failed once that way, on bad_input_jitter_negative.
# The folders are made at configure time, so no job creates a shared parent, and their paths are kept
# short, because Open MPI puts its sockets inside them (a Unix socket path holds at most 107 bytes).
function(sinew_private_mpi_session_dirs)
  set(base ${PROJECT_BINARY_DIR}/ompi)
  string(LENGTH "${base}" length)
  if(length GREATER 60)
    string(MD5 build_hash "${PROJECT_BINARY_DIR}")
    string(SUBSTRING "${build_hash}" 0 8 build_hash)
    set(base /tmp/sinew-ompi-${build_hash})
  endif()
  get_property(tests DIRECTORY PROPERTY TESTS)
  foreach(test IN LISTS tests)
    string(MD5 name_hash "${test}")
    string(SUBSTRING "${name_hash}" 0 10 name_hash)
    file(MAKE_DIRECTORY ${base}/${name_hash})
    set_property(TEST ${test} APPEND PROPERTY ENVIRONMENT "OMPI_MCA_orte_tmpdir_base=${base}/${name_hash}")
  endforeach()
endfunction()
