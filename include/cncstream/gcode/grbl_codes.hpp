#pragma once
// GRBL 1.1 status (error:N) and alarm (ALARM:N) numbers: the firmware's
// protocol, which the interpreter and the simulator answer with. What each
// number means (and what to do about it) is data in the firmware profiles
// (firmware-profiles/*.toml, read in the protocol layer), the one table of
// texts; real GRBL also sends numbers only.

namespace cncstream::grbl {

enum Status : int {
  kOk = 0,
  kExpectedCommandLetter = 1,
  kBadNumberFormat = 2,
  kInvalidStatement = 3,
  kNegativeValue = 4,
  kSettingDisabled = 5,
  kSettingStepPulseMin = 6,
  kSettingReadFail = 7,
  kIdleError = 8,
  kSystemGcLock = 9,
  kSoftLimitError = 10,
  kOverflow = 11,
  kMaxStepRateExceeded = 12,
  kCheckDoor = 13,
  kLineLengthExceeded = 14,
  kTravelExceeded = 15,
  kInvalidJogCommand = 16,
  kSettingDisabledLaser = 17,
  kUnsupportedCommand = 20,
  kModalGroupViolation = 21,
  kUndefinedFeedRate = 22,
  kCommandValueNotInteger = 23,
  kAxisCommandConflict = 24,
  kWordRepeated = 25,
  kNoAxisWords = 26,
  kInvalidLineNumber = 27,
  kValueWordMissing = 28,
  kUnsupportedCoordSys = 29,
  kG53InvalidMotionMode = 30,
  kAxisWordsExist = 31,
  kNoAxisWordsInPlane = 32,
  kInvalidTarget = 33,
  kArcRadiusError = 34,
  kNoOffsetsInPlane = 35,
  kUnusedWords = 36,
  kG43DynamicAxisError = 37,
  kMaxValueExceeded = 38,
};

enum Alarm : int {
  kAlarmHardLimit = 1,
  kAlarmSoftLimit = 2,
  kAlarmAbortCycle = 3,
  kAlarmProbeFailInitial = 4,
  kAlarmProbeFailContact = 5,
  kAlarmHomingFailReset = 6,
  kAlarmHomingFailDoor = 7,
  kAlarmHomingFailPulloff = 8,
  kAlarmHomingFailApproach = 9,
};

}  // namespace cncstream::grbl
