/* embed_example.h - the example of docs/embedding.md: the core stepped by a program of its own. */
#ifndef MVT_EMBED_EXAMPLE_H
#define MVT_EMBED_EXAMPLE_H

/* Runs the example; print receives each line of its output. 0: the person was tracked with one
 * identity within 10 cm from the third frame on. */
int mvt_embed_example(void (*print)(const char *line));

#endif
