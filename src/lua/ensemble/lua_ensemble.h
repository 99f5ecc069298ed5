/*
 * lua_ensemble.h - what a host program (dfle-mpi) needs of dfle.ensemble
 * beyond the host interface (lua/drive/lua_drive.h): the evaluator
 * another process opens from the key rank 0 sends (not installed).
 */
#ifndef DFLE_LUA_ENSEMBLE_H
#define DFLE_LUA_ENSEMBLE_H

#include "dfle/evaluator.h"
#include "lua/drive/lua_drive.h"

/* The evaluator of the ensemble that `key` names (an ensemble evaluator's
 * dfle_evaluator.key): its workers make states with host->open_state and
 * replay the script up to that dfle.ensemble call, checking that they
 * build the same ensemble.  *ev is valid until
 * dfle_lua_ensemble_remote_free(*ev).  DFLE_EINVAL for a key that names
 * no ensemble of this binding, DFLE_ENOMEM. */
int dfle_lua_ensemble_remote(const dfle_lua_host *host, const char *key, dfle_evaluator **ev,
                             dfle_error *err);
void dfle_lua_ensemble_remote_free(dfle_evaluator *ev);

#endif
