# flexfarm_library(NAME PUBLIC deps... [PRIVATE deps...]): the folder NAME/ becomes the static library
# ff_NAME (PRIVATE: libraries only its sources use; their headers stay out of its users' builds).
# A folder without sources yet becomes an interface library, so later folders can already link it.
function(flexfarm_library name)
  cmake_parse_arguments(ARG "" "" "PUBLIC;PRIVATE" ${ARGN})
  file(GLOB srcs CONFIGURE_DEPENDS ${PROJECT_SOURCE_DIR}/${name}/*.cpp)
  if(srcs)
    add_library(ff_${name} STATIC ${srcs})
    target_include_directories(ff_${name} PUBLIC ${PROJECT_SOURCE_DIR})
    target_link_libraries(ff_${name} PUBLIC ${ARG_PUBLIC} PRIVATE ${ARG_PRIVATE})
    # Under FLEXFARM_FUZZ the libraries carry libFuzzer's coverage hooks (the test programs do not).
    if(FLEXFARM_FUZZ)
      target_compile_options(ff_${name} PRIVATE -fsanitize=fuzzer-no-link)
    endif()
  else()
    add_library(ff_${name} INTERFACE)
    target_include_directories(ff_${name} INTERFACE ${PROJECT_SOURCE_DIR})
    target_link_libraries(ff_${name} INTERFACE ${ARG_PUBLIC})
  endif()
endfunction()

# The test programs' own sources at -O1: they compile in two thirds of the time -O3 takes (measured on
# tests/apps/farm_test.cpp, 8.3 s against 13.7 s), and their work is in the libraries they call, which keep
# the build's optimisation. .ci/sanitize sets -O0.
set(FLEXFARM_TEST_CXX_FLAGS "-O1" CACHE STRING "Extra compile flags for the test programs' own sources")

# The tests that take more than a few seconds in a release build (gtest filter patterns): labelled
# `slow`, the rest `fast` (and those, like the mapped truth comparison and the truth simulator's longer
# runs, 30 to 50 times slower under the sanitizers: 20-50 s each there). The sanitizer build (.ci/sanitize) runs the fast ones of every program.
set(FLEXFARM_SLOW_TESTS
  "HiddenEffectSuite.*:DiagnosisAcceptance.*:FbtbTitanCli.*:ArmHydraulics.TheFixedStepIntegratorsFollowCvodeOnATwoLinkArmWithAHydraulicShoulder:ArmHydraulics.AVariantGivesTheSameBitsAloneAndInAnyLaneOfABatch:ArmHiddenEffect.*:ArmHiddenEffectSuite.*:ArmCli.DiagnoseFindsFrictionHiddenAtTheElbowAndCalibrateAddsIt:ArmSimulate.TheFixedStepIntegratorsFollowCvodeOnTheTwoLinkFlexibleArm:TruthCompare.TheMappedFlexfarmModelExplainsEachHiddenEffect:TruthCompare.TheHydraulicRigsModelExplainsTheHydraulicTruth:TruthSim.MatchesTheIndependentReferenceTrace:TruthSim.InLoopHubAngleDelayChangesTheResponse:TruthSim.ConservesEnergyWithoutControlAndDamping:EmpsLoop.*:Emps.*:CalibrateLoop.*:Diagnose.*:Farm.ThreadCountAndLaneWidthDoNotChangeResults:Farm.ShardsMergeToTheSameTable:Farm.MpiTwoRanksMatchOneProcess:Farm.MpiRankKilledMidRunStopsNamingItAndResumeWithOtherRanksCompletes:Farm.KilledAtRandomMomentsAndResumedLosesAndRepeatsNothing:Farm.DiskFullMidRunKeepsTheJournalWholeAndResumeCompletes:Cli.DiagnoseJsonHasTheBaselineTheRankingAndTheVerdict:ArmDiagnosisAcceptance.*:TruthArm.EnergyIsConservedWithoutDampingOrControl"
  CACHE STRING "gtest filter of the slow tests (labelled slow; the others fast)")

# flexfarm_tests(FOLDER LIBS...): one GoogleTest program per folder of tests/ (its *_test.cpp files and
# their helpers), each test registered with ctest, labelled fast or slow.
function(flexfarm_tests folder)
  file(GLOB srcs CONFIGURE_DEPENDS ${PROJECT_SOURCE_DIR}/tests/${folder}/*.cpp)
  if(NOT srcs)
    return()
  endif()
  add_executable(test_${folder} ${srcs})
  target_link_libraries(test_${folder} PRIVATE ${ARGN} GTest::gtest_main)
  # Extra flags for the test programs' own sources only (.ci/sanitize: -O0, half the compile time;
  # the libraries they test keep the build's optimisation).
  if(FLEXFARM_TEST_CXX_FLAGS)
    separate_arguments(test_flags UNIX_COMMAND "${FLEXFARM_TEST_CXX_FLAGS}")
    target_compile_options(test_${folder} PRIVATE ${test_flags})
  endif()
  target_compile_definitions(test_${folder} PRIVATE
    FLEXFARM_SOURCE_DIR="${PROJECT_SOURCE_DIR}"
    FLEXFARM_BINARY="$<TARGET_FILE:flexfarm>")
  add_dependencies(test_${folder} flexfarm)
  # Every run a test makes records itself in the build's own run history, never in the user's.
  set(history ENVIRONMENT FLEXFARM_HISTORY=${CMAKE_CURRENT_BINARY_DIR}/history)
  gtest_discover_tests(test_${folder} WORKING_DIRECTORY ${CMAKE_CURRENT_BINARY_DIR} DISCOVERY_TIMEOUT 60
    TEST_FILTER "-${FLEXFARM_SLOW_TESTS}" PROPERTIES LABELS fast ${history})
  # The slow tests start first (a high COST): on a fresh tree, with no timings yet, ctest would
  # otherwise start the longest (minutes) last, beside nothing.
  gtest_discover_tests(test_${folder} WORKING_DIRECTORY ${CMAKE_CURRENT_BINARY_DIR} DISCOVERY_TIMEOUT 60
    TEST_FILTER "${FLEXFARM_SLOW_TESTS}" PROPERTIES LABELS slow COST 1000 ${history})
endfunction()
