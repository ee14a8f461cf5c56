/* Shared by the C consumer's files: the failure count, the checks, the test scene. */
#ifndef VOLLEY_CONSUMER_C_H
#define VOLLEY_CONSUMER_C_H

#include <volley/volley.h>

extern int failures;
/* Counts a failure (and prints the first 20) when !ok. */
void check(int ok, const char* what, int index);
/* Checks status == expected and, on failure, that the message names the function. */
void expect(volley_status status, volley_status expected, const char* function);
/* The scene of scene.h: floor (geometry 0), table (1), polygon (2); not committed. */
volley_scene* make_scene(void);

/* consumer_c_scene_model.c */
void check_geometries(void);
void check_refit(void);
void check_save_load(void);
void check_masks(void);
void check_instances(void);

/* consumer_c_queries.c */
void check_queries(void);

#endif
