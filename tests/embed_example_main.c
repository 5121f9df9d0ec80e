/* The host's main of docs/embed_example.c (CTest: embed_example). */
#include <stdio.h>

#include "embed_example.h"

static void print(const char *line)
{
    fputs(line, stdout);
}

int main(void)
{
    return mvt_embed_example(print);
}
