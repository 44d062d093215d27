# Included by ctest after the discovered tests (tests/CMakeLists.txt): the longest tests' COST, so
# that `ctest -j2` in a fresh build folder, which has no timing data of its own yet
# (Testing/Temporary/CTestCostData.txt), starts them first instead of in declaration order. Without
# it the bench's tests (one at a time, RESOURCE_LOCK ponyhop_bench), BenchSmoke's 12 s run among
# them, came last and ran on one core while the other stood idle. ctest runs the highest COST
# first; once it has timed a test, its own figure replaces the one here. A name that no longer
# exists is ignored: after renaming one of these tests, rename it here too.
# The figures: seconds a test took in a fresh clone's `ctest -j2` (session 28, 84d8b80).
set_tests_properties(BenchSmoke.RunsAndWritesItsFiles PROPERTIES COST 12)
set_tests_properties(Presets.ShippedPresetsLoadAndChangeTheLook PROPERTIES COST 3.6)
set_tests_properties(BenchRender.WritesEveryConfigurationAndItsRatioToTheFloor PROPERTIES COST 3.0)
set_tests_properties(HeadStress.TheSnapClipNeitherPassesThroughNorPopsOut PROPERTIES COST 2.8)
set_tests_properties(WindowTest.ViewIsDraftWhileMovingAndFinalWhenStill PROPERTIES COST 2.8)
set_tests_properties(HopperReference.ConvergesOverThreeStancesWithAFixedControlRateAndLocatedTouchdowns
                     PROPERTIES COST 2.4)
set_tests_properties(MeshIsolation.ACorruptedPlyIsAMessage PROPERTIES COST 2.1)
set_tests_properties(MeshIsolation.CrashAbortHangAndMemoryOfTheChildAreMessages PROPERTIES COST 2.1)
set_tests_properties(PanelTest.EachChainOfATwoChainSceneHasItsOwnFieldsAndLinksToPull PROPERTIES COST 2.1)
set_tests_properties(HopperScene.PonytailOnTheHopperHopsForThirtySeconds PROPERTIES COST 1.7)
set_tests_properties(WindowTest.RunUnderXvfbShowsTheSceneAndThePanel PROPERTIES COST 1.5)
set_tests_properties(Video.ContainerFollowsTheExtensionOrIsRefused PROPERTIES COST 1.5)
set_tests_properties(HeadCollisionsScene.JointConesAndTwistLimitsHold PROPERTIES COST 1.5)
set_tests_properties(RenderFarm.TwoChunksThroughParallelMatchOneRunByteForByte PROPERTIES COST 1.5)
set_tests_properties(HopperRun.SpeedRangeThatTracksWithinTenPercent PROPERTIES COST 1.4)
set_tests_properties(Install.InstalledExecutableRunsFromAnyFolder PROPERTIES COST 1.3)
set_tests_properties(BenchLoops.AShortRunClosesEveryLoopAndAStoppedRowIsAFindingNotAFailure PROPERTIES COST 1.2)
