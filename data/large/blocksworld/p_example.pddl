(define (problem blocksworld-p-example)
  (:domain blocksworld-4ops)
  (:objects
    b1 b2 b3 b4
  )
  (:init
    (on-table b2)
    (on-table b3)
    (on b4 b3)
    (on b1 b4)
    (clear b2)
    (clear b1)
    (arm-empty)
  )
  (:goal (and
    (on b1 b4)
    (on b3 b2)
  ))
)
