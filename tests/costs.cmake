# The long tests first: CTest runs a set in descending COST, and on a clean clone (CI) it has no
# record of earlier runs (Testing/Temporary/CTestCostData.txt), so without these the longest
# would start last and run alone on one core at the end. Seconds on
# 2 cores, the larger of the Release and the sanitizer build's (there about 4 times Release);
# a name a build does not have is passed over.
foreach(entry IN ITEMS
    Readme.TourRunsAsWritten:210 Ngc.OptimizeFeedKeepsTheCorpusMotion:175
    OptimizeFeed.ForceAndTorqueCapsHold:145
    Optimize.FindsTheLargestFeedWhoseChipStaysBelowTheLimit:140
    Io.FailedWritesLeaveNothingAndNameTheFile:120 Report.OpensInChromium:100
    Cli.CtrlCStopsCleanlyAndLeavesNoHalfWrittenFile:95 Analysis.SteadyCycleAtSmallSteps:90
    CurvedSlot.EveryFamilyHoldsItsStraightChipAlongTheBend:85
    Forces.CalibrationRoundTripRecoversCoefficientsAndRunout:80
    OptimizeFeed.DescentsIntoTheStockNeverSpeedUp:45 Python.sweep:45
    OptimizeFeed.AStockMeshIsTheStock:45 Cli.MemoryEstimatesMatchThePeak:40
    Ngc.CutterCompensationEqualsLinuxCncsOnRandomContours:40
    Pockets.LinuxCncReadsThemTheAreaIsClearedAndTheTargetHolds:40
    Cli.ForcesCalibrateAndMaterials:35 Optimize.ParetoSetIsNonDominated:30
    Planner.ToolStaysInsideAndCutsTheWholeSlot:30 Ngc.MovesEqualLinuxCncsOnTheCorpus:27
    Ngc.LinuxCncSamplesReadAsLinuxCnc:27 Ngc.ProgramsByOthersReadAsLinuxCnc:40)
  string(REPLACE ":" ";" pair "${entry}")
  list(GET pair 0 name)
  list(GET pair 1 cost)
  # Included twice: by tests/CMakeLists.txt for the tests it declares (where a name it does
  # not declare would be an error), and by ctest for the GoogleTest ones (which it ignores).
  if(NOT TROCHOMILL_COSTS_AT_CONFIGURE)
    set_tests_properties(${name} PROPERTIES COST ${cost})
  elseif(TEST ${name})
    set_tests_properties(${name} PROPERTIES COST ${cost})
  endif()
endforeach()
