# cmake -DNPM=... -DWEB_DIR=... -DSTAMP=... -P npm-ci.cmake
# Installs web/node_modules with `npm ci` only when package-lock.json differs from the one it was
# last installed from (a hash kept inside node_modules): every build folder shares web/node_modules,
# and npm ci deletes and reinstalls it whole, so each build running it would cost each its minute.
file(SHA256 "${WEB_DIR}/package-lock.json" lock_hash)
set(installed_file "${WEB_DIR}/node_modules/.fba-package-lock.sha256")
set(installed_hash "")
if(EXISTS "${installed_file}")
  file(READ "${installed_file}" installed_hash)
endif()
if(NOT installed_hash STREQUAL lock_hash)
  message(STATUS "npm ci in ${WEB_DIR} (package-lock.json changed)")
  execute_process(COMMAND "${NPM}" ci --no-audit --no-fund --loglevel=error
                  WORKING_DIRECTORY "${WEB_DIR}" RESULT_VARIABLE rc)
  if(NOT rc EQUAL 0)
    message(FATAL_ERROR "npm ci failed in ${WEB_DIR} (${rc}): is the npm registry reachable? The rest of fba builds without the page: -DFBA_BUILD_WEB=OFF")
  endif()
  file(WRITE "${installed_file}" "${lock_hash}")
endif()
file(TOUCH "${STAMP}")
