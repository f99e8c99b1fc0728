// The settings types of scenes and edits, each described once (core/schema.h): lights, wind
// emitters, painted strokes, the wind, the output settings, and rigid transforms. Scene files,
// edit scripts, session loading and the studio all read, write and check these through the
// functions below, so a key means the same and has the same limits everywhere
// (docs/scene-format.md, docs/edit-scripts.md).
//
// Directions are kept as written (a light's, an emitter's); what uses them normalises them
// (normalised() below), so that an edit read back from its own JSON is the same value.
#pragma once

#include "tendril/core/json_reader.h"
#include "tendril/core/schema.h"
#include "tendril/env/environment.h"
#include "tendril/scene/scene.h"

#include <optional>
#include <string>

namespace tendril::scene {

const schema::Schema<env::Light>& lightSchema();
const schema::Schema<env::WindEmitter>& emitterSchema();
const schema::Schema<env::Stroke>& strokeSchema();
// The wind's own keys; "emitters" (emitterSchema) and "sph" are read beside them.
const schema::Schema<env::WindSettings>& windSchema();
// The scene's "output" object, and its "wind_animation" object (which, when present, defaults
// to 4 s).
const schema::Schema<OutputSettings>& outputSchema();
const schema::Schema<OutputSettings>& windAnimationSchema();

// The one reader of each settings type. Strict, but they do not finish `o`: an edit's object
// holds keys of its own.
env::Light readLight(JsonObject& o);
env::WindEmitter readEmitter(JsonObject& o);
env::Stroke readStroke(JsonObject& o);
// The wind's keys and its "emitters" (each emitter object finished); not "sph".
env::WindSettings readWind(JsonObject& o);
// Reads "output" and its "wind_animation"; finishes both.
OutputSettings readOutput(JsonObject& o);

// The JSON the readers read back to the same value.
Json lightJson(const env::Light& light);
Json emitterJson(const env::WindEmitter& emitter);
Json strokeJson(const env::Stroke& stroke);

// Values that did not come from a reader (saved states, widgets, code) checked against the
// readers' limits: nullopt, or "/<key>: <the reader's message>".
std::optional<std::string> checkLight(const env::Light& light);
std::optional<std::string> checkEmitter(const env::WindEmitter& emitter);
std::optional<std::string> checkStroke(const env::Stroke& stroke);
// The wind's own keys and every emitter ("/emitters/<i>/<key>: ...").
std::optional<std::string> checkWind(const env::WindSettings& wind);

// With the direction normalised, as the environment uses it (the value must pass the check).
env::Light normalised(env::Light light);
env::WindEmitter normalised(env::WindEmitter emitter);

// A rigid transform: "position" [x, y, z] (m; edit scripts before this build called it
// "translation", still read) and "rotation", either [x, y, z] Euler angles in degrees (about
// X, then Y, then Z) or a unit quaternion [w, x, y, z]. A quaternion is kept as written unless
// `normalise` (edits normalise when applied, so that they replay bit for bit).
RigidTransform readTransform(JsonObject& o, bool normalise);
// "position" and "rotation" as a quaternion [w, x, y, z] (what readTransform reads back exactly).
void writeTransform(Json& j, const RigidTransform& t);

}  // namespace tendril::scene
