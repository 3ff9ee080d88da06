/* SPDX-License-Identifier: LGPL-2.1-or-later */
/* Aligned tables for people: a header row, columns as wide as their widest
 * cell, numbers right-aligned, optional colour per cell (not counted in the
 * width). */
#pragma once

#include <stdbool.h>
#include <stddef.h>
#include <stdio.h>

typedef struct ctl_table ctl_table;

/* Column names; a name starting with '>' is right-aligned (the '>' is not
 * printed). */
int ctl_table_new(ctl_table **ret, size_t n_columns, const char *const *names);
ctl_table *ctl_table_free(ctl_table *t);
/* Adds a cell to the current row (rows fill left to right). `color` is an
 * ANSI sequence or NULL. */
int ctl_table_add(ctl_table *t, const char *color, const char *fmt, ...) __attribute__((format(printf, 3, 4)));
size_t ctl_table_rows(const ctl_table *t);
/* Prints it; `legend`: the header line; `colors`: use the cell colours. */
void ctl_table_print(const ctl_table *t, FILE *f, bool legend, bool colors);

#define CTL_ANSI_NORMAL "\033[0m"
#define CTL_ANSI_BOLD "\033[1m"
#define CTL_ANSI_RED "\033[0;31m"
#define CTL_ANSI_GREEN "\033[0;32m"
#define CTL_ANSI_YELLOW "\033[0;33m"
#define CTL_ANSI_GREY "\033[0;38;5;245m"
#define CTL_ANSI_HEADER "\033[1;4m"
