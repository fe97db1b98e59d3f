//! Variables of the kinds a signal can be (Real/Float64, Integer/Int32, Boolean) read and set as doubles, one FMI
//! call per kind: [`Numbers`] groups their value references by kind once, with the buffers each kind's call needs,
//! so that a step allocates nothing. An Integer takes a double rounded to the nearest integer (within the 32-bit
//! range), a Boolean is true from 0.5 up; both read back as exact doubles (a Boolean as 0 or 1).

use crate::description::ValueKind;
use crate::{FmiError, Inner, Instance};

/// One kind's value references, where each sits among all the values, and its call's buffer.
#[derive(Debug, Clone, Default)]
struct Group<T> {
    refs: Vec<u32>,
    /// The index into the caller's values of each reference.
    at: Vec<usize>,
    buffer: Vec<T>,
}

impl<T: Copy + Default> Group<T> {
    fn push(&mut self, value_reference: u32, index: usize) {
        self.refs.push(value_reference);
        self.at.push(index);
        self.buffer.push(T::default());
    }
}

/// Variables of mixed numeric kinds, in the caller's order, read and set as doubles.
#[derive(Debug, Clone, Default)]
pub struct Numbers {
    reals: Group<f64>,
    integers: Group<i32>,
    /// FMI 2's booleans are C ints.
    booleans2: Group<i32>,
    /// FMI 3's booleans are C bools, kept as their byte.
    booleans3: Group<u8>,
    len: usize,
}

impl Numbers {
    /// The variables (kind, value reference), in the order their values will be given and read. Panics on a kind
    /// that is not a number ([`ValueKind::is_number`]): the callers choose the variables.
    pub fn new(variables: impl IntoIterator<Item = (ValueKind, u32)>) -> Self {
        let mut n = Self::default();
        for (index, (kind, value_reference)) in variables.into_iter().enumerate() {
            match kind {
                ValueKind::Real => n.reals.push(value_reference, index),
                ValueKind::Integer => n.integers.push(value_reference, index),
                ValueKind::Boolean => {
                    n.booleans2.push(value_reference, index);
                    n.booleans3.push(value_reference, index);
                }
                ValueKind::Other(name) => panic!("a {name} variable is not a number"),
            }
            n.len = index + 1;
        }
        n
    }

    /// How many variables.
    pub fn len(&self) -> usize {
        self.len
    }

    /// Whether there are none.
    pub fn is_empty(&self) -> bool {
        self.len == 0
    }
}

/// A double as an FMI integer: rounded to the nearest, within the 32-bit range (NaN is 0).
pub fn to_integer(value: f64) -> i32 {
    value.round().clamp(i32::MIN as f64, i32::MAX as f64) as i32
}

/// A double as an FMI Boolean: true from 0.5 up.
pub fn to_boolean(value: f64) -> bool {
    value >= 0.5
}

impl Instance {
    /// Set the variables of `numbers` to `values` (one per variable, in its order).
    pub fn set_numbers(&mut self, numbers: &mut Numbers, values: &[f64]) -> Result<(), FmiError> {
        assert_eq!(values.len(), numbers.len, "one value per variable");
        let reals = &mut numbers.reals;
        for (slot, &k) in reals.buffer.iter_mut().zip(&reals.at) {
            *slot = values[k];
        }
        let integers = &mut numbers.integers;
        for (slot, &k) in integers.buffer.iter_mut().zip(&integers.at) {
            *slot = to_integer(values[k]);
        }
        if !reals.refs.is_empty() {
            self.set_reals(&reals.refs, &reals.buffer)?;
        }
        let (b2, b3) = (&mut numbers.booleans2, &mut numbers.booleans3);
        match &mut self.inner {
            Inner::V2(i) => {
                if !integers.refs.is_empty() {
                    i.set_integers(&integers.refs, &integers.buffer)?;
                }
                for (slot, &k) in b2.buffer.iter_mut().zip(&b2.at) {
                    *slot = i32::from(to_boolean(values[k]));
                }
                if !b2.refs.is_empty() {
                    i.set_booleans(&b2.refs, &b2.buffer)?;
                }
            }
            Inner::V3(i) => {
                if !integers.refs.is_empty() {
                    i.set_integers(&integers.refs, &integers.buffer)?;
                }
                for (slot, &k) in b3.buffer.iter_mut().zip(&b3.at) {
                    *slot = u8::from(to_boolean(values[k]));
                }
                if !b3.refs.is_empty() {
                    i.set_booleans(&b3.refs, &b3.buffer)?;
                }
            }
        }
        Ok(())
    }

    /// Read the variables of `numbers` into `values` (one per variable, in its order).
    pub fn get_numbers(&mut self, numbers: &mut Numbers, values: &mut [f64]) -> Result<(), FmiError> {
        assert_eq!(values.len(), numbers.len, "one value per variable");
        let reals = &mut numbers.reals;
        if !reals.refs.is_empty() {
            self.get_reals(&reals.refs, &mut reals.buffer)?;
        }
        let integers = &mut numbers.integers;
        let (b2, b3) = (&mut numbers.booleans2, &mut numbers.booleans3);
        match &mut self.inner {
            Inner::V2(i) => {
                if !integers.refs.is_empty() {
                    i.get_integers(&integers.refs, &mut integers.buffer)?;
                }
                if !b2.refs.is_empty() {
                    i.get_booleans(&b2.refs, &mut b2.buffer)?;
                }
                for (&v, &k) in b2.buffer.iter().zip(&b2.at) {
                    values[k] = f64::from(u8::from(v != 0));
                }
            }
            Inner::V3(i) => {
                if !integers.refs.is_empty() {
                    i.get_integers(&integers.refs, &mut integers.buffer)?;
                }
                if !b3.refs.is_empty() {
                    i.get_booleans(&b3.refs, &mut b3.buffer)?;
                }
                for (&v, &k) in b3.buffer.iter().zip(&b3.at) {
                    values[k] = f64::from(u8::from(v != 0));
                }
            }
        }
        for (&v, &k) in reals.buffer.iter().zip(&reals.at) {
            values[k] = v;
        }
        for (&v, &k) in integers.buffer.iter().zip(&integers.at) {
            values[k] = f64::from(v);
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn kinds_are_grouped_in_the_callers_order() {
        let n = Numbers::new([
            (ValueKind::Integer, 7),
            (ValueKind::Real, 1),
            (ValueKind::Boolean, 3),
            (ValueKind::Real, 2),
        ]);
        assert_eq!(n.len(), 4);
        assert_eq!((n.reals.refs.as_slice(), n.reals.at.as_slice()), ([1, 2].as_slice(), [1, 3].as_slice()));
        assert_eq!((n.integers.refs.as_slice(), n.integers.at.as_slice()), ([7].as_slice(), [0].as_slice()));
        assert_eq!((n.booleans2.refs.as_slice(), n.booleans3.at.as_slice()), ([3].as_slice(), [2].as_slice()));
        assert!(Numbers::new([]).is_empty());
    }

    #[test]
    fn doubles_become_integers_and_booleans_by_rounding() {
        assert_eq!([to_integer(2.4), to_integer(2.5), to_integer(-2.5), to_integer(f64::NAN)], [2, 3, -3, 0]);
        assert_eq!([to_integer(1e12), to_integer(-1e12)], [i32::MAX, i32::MIN]);
        assert_eq!(
            [to_boolean(0.49), to_boolean(0.5), to_boolean(-1.0), to_boolean(f64::NAN)],
            [false, true, false, false]
        );
    }

    #[test]
    #[should_panic(expected = "a String variable is not a number")]
    fn a_kind_that_is_no_number_is_a_callers_mistake() {
        Numbers::new([(ValueKind::Other("String"), 0)]);
    }
}
