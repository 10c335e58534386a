// Channel names of the Bricklayer bus, in one place so every process and tool agrees.
// A deployment may prefix every channel (BRICKLAYER_CHANNEL_PREFIX) to share a network with another
// exhibit; use channel() rather than the bare constants when publishing or subscribing.
#pragma once

#include <string>

namespace bricklayer {

inline constexpr const char* kImageChannel = "BL_IMAGE";            // image_t, camera/simcam -> vision
inline constexpr const char* kStackChannel = "BL_STACK";            // stack_t, vision -> prediction
inline constexpr const char* kPredictionChannel = "BL_PREDICTION";  // prediction_t, prediction -> projection
inline constexpr const char* kTimingChannel = "BL_TIMING";          // timing_t, any module
inline constexpr const char* kHeartbeatChannel = "BL_HEARTBEAT";    // heartbeat_t, every module, 1 Hz
inline constexpr const char* kCommandChannel = "BL_COMMAND";        // command_t, operator/tools -> modules
inline constexpr const char* kCalibrationChannel = "BL_CALIBRATION";  // calibration_t
inline constexpr const char* kRoundChannel = "BL_ROUND";            // round_t, projection
inline constexpr const char* kProjectorChannel = "BL_PROJECTOR";    // projector_state_t, projection -> simcam, calibration
// What the projector shows, small (a 320 px wide JPEG every 2 s of the runtime clock), source "projector":
// for the operator's status page, which cannot see the projection from the phone.
inline constexpr const char* kProjectorImageChannel = "BL_PROJECTOR_IMAGE";  // image_t, projection -> status
inline constexpr const char* kPreviewChannel = "BL_PREVIEW";        // collapse_preview_t, planner
inline constexpr const char* kHintChannel = "BL_HINT";              // hint_t, planner
inline constexpr const char* kTruthChannel = "BL_TRUTH";            // stack_t, simcam: the true stack of each frame
inline constexpr const char* kConfigChannel = "BL_CONFIG";          // node_config_t, every node at start and every 10 s
// The study session's (modules/study) that a stage reads or writes: projection shows the session's
// instruction and sends the subject's "done". The other study channels are in bricklayer/study/channels.h.
inline constexpr const char* kStudySessionChannel = "BL_STUDY_SESSION";  // study_session_t, session driver
inline constexpr const char* kStudyProblemChannel = "BL_STUDY_PROBLEM";  // study_problem_t, session driver -> projection
inline constexpr const char* kStudyCommandChannel = "BL_STUDY_COMMAND";  // study_command_t, experimenter/projection -> driver

// The channel name with the deployment's prefix (environment BRICKLAYER_CHANNEL_PREFIX, default none).
std::string channel(const char* name);

}  // namespace bricklayer
